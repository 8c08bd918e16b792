// The laws (8), (9), (10) on the first r rows of an extended task (mirrors
// clik/loop/laws.py and Tracker.law_velocity). Workspaces are allocated once, at
// construction: velocity() allocates nothing.
#pragma once

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <vector>

#include "tasks/extended_task.hpp"
#include "types.hpp"

namespace clik {

// Damping starts when a singular value falls below this fraction of sigma_max(J).
constexpr double CONDITION_RATIO = 0.01;
// Largest joint step [rad or m] each level of law (10) may ask for in one sample.
constexpr double STEP_BUDGET = 0.02;
// A constraint direction counts above this singular value, relative to max(scale, 1).
constexpr double RANK_TOLERANCE = 1e-9;

struct LawSettings {
  LawKind kind = LawKind::transpose;
  double damping = 0.0;   // lambda_0 of law (10)
  double dt = 1e-3;       // [s]
  double beta_max = 0.0;  // bound on the nonlinear law's extra gain [1/s]
  // Whether law (10)'s task-level step budget counts in its unrealised fraction (the
  // paper's law); false with the joint speed limits: measured before it.
  bool budget_blocks = true;
};

class Law {
 public:
  // rows: the most rows an extended task will hold; nv: joint velocity size. Law (10)
  // gets one constraint block and SVD workspace per possible count of active
  // constraint rows (1..rows, and rows <= m + nv): the count changes from sample to
  // sample, and an SVD resized to it would reallocate.
  Law(const LawSettings& settings, int rows, int nv);

  // Joint velocity [rad/s] of the law on the first r rows of ext into qdot.
  // Returns law (10)'s unrealised fraction of the task demand
  // |b - J qdot| / |b| (0 when tracked exactly), 0 for laws (9) and (8).
  double velocity(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot);

  const LawSettings& settings() const { return s_; }

  // Law (10)'s constraint level qdot_c of the last velocity() (0 without constraint
  // rows): the speed step's part to keep first.
  const Vec& constraint_part() const { return qdot_c_; }

 private:
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
};

}  // namespace clik
