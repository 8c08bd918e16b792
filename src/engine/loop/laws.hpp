// The laws (8), (9), (10) on the first r rows of an extended task (mirrors
// clik/loop/laws.py and Tracker.law_velocity). Workspaces are allocated once, at
// construction: velocity() allocates nothing.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <vector>

#include "tasks/extended_task.hpp"
#include "types.hpp"

namespace clik {

// Damping starts when a singular value falls below this fraction of sigma_max(J).
constexpr double CONDITION_RATIO = 0.01;
// A level of law (10) of at most this many rows has a fixed-capacity eigensolver, which
// allocates nothing (Eigen's dynamic one allocates in each tridiagonalisation).
constexpr int MAX_EIGEN_ROWS = 48;
using EigenMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor,
                               MAX_EIGEN_ROWS, MAX_EIGEN_ROWS>;
// Largest joint step [rad or m] each level of law (10) may ask for in one sample.
constexpr double STEP_BUDGET = 0.02;
// A constraint direction counts above this singular value, relative to max(scale, 1).
constexpr double RANK_TOLERANCE = 1e-9;
// A level's direction counts when its eigenvalue of JN JN^T is above this fraction of the
// level's squared scale too: rounding leaves about 1e-16 n |J_l|^2 on the zero ones
// (clik/loop/levels.py's GRAM_TOLERANCE).
constexpr double GRAM_TOLERANCE = 1e-12;

struct LawSettings {
  LawKind kind = LawKind::transpose;
  double damping = 0.0;   // lambda_0 of law (10)
  double dt = 1e-3;       // [s]
  double beta_max = 0.0;  // bound on the nonlinear law's extra gain [1/s]
  // Whether law (10)'s task-level step budget counts in its unrealised fraction (the
  // paper's law); false with the joint speed limits: measured before it.
  bool budget_blocks = true;
};

// Law (10)'s priority levels and objectives (issue 24; clik/loop/levels.py): the end row
// of each level of the task rows (strictly increasing, the last = every task row), and
// the level of each objective of eq. (5). Empty ends: one level of every task row.
struct LevelPlan {
  std::vector<int> ends;
  std::vector<int> objective_levels;
  // Where each task row of J may not be zero, [lo[i], hi[i]) (m each; lo nv, hi 0: a
  // row that is always zero), from the tasks' structure (the joints supporting a frame,
  // a posture row's joint). Empty: found in each sample's J.
  std::vector<int> lo, hi;
};

class Law {
 public:
  // rows: the most rows an extended task will hold; nv: joint velocity size. Law (10)
  // gets one constraint block and SVD workspace per possible count of active
  // constraint rows (1..rows, and rows <= m + nv): the count changes from sample to
  // sample, and an SVD resized to it would reallocate.
  Law(const LawSettings& settings, int rows, int nv);
  // With levels and objectives (law (10) only): m, the task rows (plan.ends' last).
  Law(const LawSettings& settings, int rows, int nv, int m, const LevelPlan& plan);

  // Joint velocity [rad/s] of the law on the first r rows of ext into qdot.
  // Returns law (10)'s unrealised fraction of the task demand
  // |b - J qdot| / |b| (0 when tracked exactly), 0 for laws (9) and (8).
  double velocity(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot);

  const LawSettings& settings() const { return s_; }

  // Law (10)'s constraint level qdot_c of the last velocity() (0 without constraint
  // rows): the speed step's part to keep first.
  const Vec& constraint_part() const { return qdot_c_; }

  // Whether law (10) runs by levels (clik/loop/levels.py's prioritized_levels): several
  // levels, one of more than MAX_TASK_ROWS rows, or objectives.
  bool by_levels() const { return by_levels_; }
  int levels() const { return static_cast<int>(ends_.size()); }
  // The last velocity()'s parts by levels (1 + L, nv): the constraint level's, then each
  // level's (its objectives included): the speed step's parts (by_levels() only).
  const Mat& parts() const { return parts_; }
  // Each objective's z [rad/s] (nv) of this sample, written by the run before velocity().
  std::vector<Vec>& objective_z() { return z_; }

 private:
  double prioritized_levels(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot);
  void level_constraints(const ExtendedTask& ext, int v, double scale1);
  double unrealised_rows(const ExtendedTask& ext, int a, int b, const Vec& x);
  double row_times(const ExtendedTask& ext, int i, const Vec& x) const;
  double prioritized(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot);
  void constraint_level(const ExtendedTask& ext, int v, double epsilon);
  void one_constraint_level(const ExtendedTask& ext, double epsilon);
  void damped_solve(const TaskMat& A, const Vec& b, double epsilon, Vec& y);
  void within_budget(Vec& qdot) const;
  double unrealised(const ExtendedTask& ext, const Eigen::Ref<const Vec>& qdot);

  LawSettings s_;
  double scale_ = 0.0;  // sqrt of the largest squared row norm of the task's J
  Vec b_, work_, jte_, qdot_c_, qdot_t_, rest_, y_, w_, gain_, tmp_;
  Eigen::MatrixXd JN_;
  TaskMat A_;  // m x m, m <= MAX_TASK_ROWS
  Eigen::SelfAdjointEigenSolver<TaskMat> eig_;
  // constraint_[v - 1]: the v active constraint rows C and their SVD (v >= 2; one
  // row has a closed form).
  struct ConstraintBlock {
    ConstraintBlock(int v, int nv);
    Eigen::MatrixXd C;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd;
  };
  std::vector<ConstraintBlock> constraint_;

  // By levels: one workspace per level, sized once (its rows never change).
  struct Level {
    Level(int n, int nv);
    Mat M;                 // J_l Z: the level in the free directions' coordinates (n, <= nv)
    Eigen::MatrixXd A, S;  // M M^T = JN JN^T, a factorisation's copy (n, n)
    Vec rest, y, tmp, work;  // work: the eigenvalue bound's (2 max(n, nv))
    std::vector<int> lo, hi;  // where each row of M may not be zero: [lo, hi)
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig;   // levels of more rows
    Eigen::SelfAdjointEigenSolver<EigenMat> eig_small;  // levels of at most MAX_EIGEN_ROWS
    bool basis = false;  // removes its directions (a level above another, or with objectives)
  };
  struct Tolerances {
    double eps2 = 0.0, d2 = 0.0;  // epsilon_l^2, lambda_0^2
    double kept = 0.0;            // a direction's eigenvalue counts above it
    double floor = 0.0;           // the regular case's eigenvalues clear it
    double top = 0.0;             // bounds the Gram matrix's diagonal (scale^2)
  };
  void solve_level(Level& lv, const double* Jl, const int* jlo, const int* jhi, double scale,
                   double* part);
  bool solve_rows(Level& lv, const double* M, const Tolerances& tol);
  bool solve_columns(Level& lv, const double* M, const Tolerances& tol);
  int solve_eigenpairs(Level& lv, const double* M, const Tolerances& tol);
  void times_rows(const double* M, int n, const double* y);
  void set_free(int q);
  void remove_directions(int p);
  bool remove_rows(const double* M, int n, const double* L, const int* lo, const int* hi);
  bool orthonormal_rows(const double* M, int n, const int* lo, const int* hi, double* L);
  // Two levels, the second of unit rows (a posture: loop/unit_level.cpp): without Z.
  bool projected_levels(const ExtendedTask& ext, int v, double& blocked);
  void project_free(const double* M1, int n1, int f, const double* L, const double* inv,
                    double* x);
  bool regular_level(const double* A, int n, double floor, double d2, double* S);
  Eigen::MatrixXd A1_;        // level 1's Gram matrix at the previous sample (n1, n1)
  double certified_ = -1.0;   // a lower bound on its smallest eigenvalue (< 0: none)
  double margin_ = 0.0;       // the shift the next certificate tries (0: from the pivots)
  bool unit_plan_ = false;  // two levels, no objective, the second's rows one column each
  std::vector<int> fpos_, fcols_, epos_;  // F: each column's place (-1: held), its columns; E
  std::vector<char> hit_;  // a free column the second level's rows reach
  Mat M1_, Pe_;  // level 1 on F (n1, f); L^-1 [M1[:, E], M1 u] (n1 rows of e + 1 values)
  Eigen::MatrixXd H_, Hs_;  // P^T P (e, e); its factor, and room for another
  Vec u_, g_, t_, s1_;     // F vectors (nv); level 1's (n1)
  bool q_ready_ = false;  // solve_rows left the level's Q in P_ (remove_rows uses it)
  bool by_levels_ = false;
  std::vector<int> ends_, zlevel_;
  std::vector<Vec> z_;
  std::vector<Level> level_;
  // Z: orthonormal basis (nv, k_) of the directions the levels above leave free (the
  // null space of the constraints' and the levels' kept rows); the identity at first.
  Eigen::MatrixXd Z_, Zn_;
  int k_ = 0;
  bool z_identity_ = true;
  Eigen::MatrixXd P_, W_, G_, Gs_;  // directions removed (k, p); their complement; M^T M
  Vec beta_, tk_;  // Householder factors; a level's x (k)
  Mat parts_;
  Vec out_, zp_;
  Vec lscale_;  // each level's scale (its largest row norm)
  std::vector<int> span_;  // remove_rows: where each row of Q may not be zero
  std::vector<int> jlo_, jhi_;  // where each task row of J may not be zero: [jlo, jhi)
  bool scan_rows_ = true;  // jlo_, jhi_ found in each sample's J (no plan.lo, plan.hi)
};

}  // namespace clik
