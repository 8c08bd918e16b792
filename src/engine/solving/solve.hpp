// Solve mode: reach one target from q0 by iterating a law to tolerance
// (mirrors its specification: clik/solving/solve_problem.py, SolveSettings and
// SolveProblem, and clik/solving/solve_mode.py, solve).
//
// The reference is held and the law iterated as a fixed-point map,
// q <- q (+) step qdot, clipped into the joint limits:
//   law (10): qdot = J^T (J J^T + lambda^2 I)^-1 e, lambda^2 = lambda_0^2 + mu |e|^2
//             (Levenberg-Marquardt);
//   law (9):  qdot = J^T e.
// A full pose's error is e = log6(oMf^-1 oMd) in the frame, with its exact
// Jacobian J = Jlog6(fMd^-1) J_local; a masked task's is the world-aligned
// error (6) (p_d - p, log3(R_d R^T)) on the task's rows, with the
// LOCAL_WORLD_ALIGNED frame Jacobian (3). An attempt that stalls or runs out
// of iterations gives way to the next start configuration.
//
// One Solver serves any number of solves of its task with its settings
// (clik/solving/compiled_solve.py keeps one per task and settings): start() begins a new
// solve of a target from q0; the restarts' random configurations are drawn by
// the caller (Python, with the seeded generator the Python engine uses) and
// handed over as rows of `starts` to run(), which continues the same solve.
// Workspaces are allocated once, at construction: a solve allocates nothing.
#pragma once

#include <pinocchio/multibody.hpp>
#include <pinocchio/spatial.hpp>

#include <Eigen/Cholesky>
#include <Eigen/SVD>

#include <vector>

#include "boundary.hpp"
#include "types.hpp"

namespace clik {

// An iteration makes progress when the error falls below this fraction of the best.
constexpr double STALL_PROGRESS = 0.999;
// Iterations without progress after which an attempt restarts.
constexpr int STALL_ITERATIONS = 15;

struct SolveSettings {
  LawKind law = LawKind::pseudoinverse;  // pseudoinverse (10) or transpose (9)
  double step = 1.0;                     // alpha dt: fraction of qdot applied per iteration
  double damping = 1e-6;                 // lambda_0
  double mu = 1e-2;                      // Levenberg-Marquardt factor
  double tolerance = 1e-4;               // position [m]
  double orientation_tolerance = 1e-3;   // orientation [rad]
  int max_iterations = 100;              // per attempt
};

// The task's frame and rows (what SolveProblem reads from the Task).
struct SolveTask {
  pinocchio::FrameIndex frame_id = 0;
  std::vector<int> rows;  // kept components of (x, y, z, rx, ry, rz), ascending
};

// The law's small linear algebra on the task rows: Rows = 6 for a full pose
// (fixed size: no loops over run-time sizes, no heap), Eigen::Dynamic for a
// masked task (1 to 6 rows).
template <int Rows>
class LawSystem {
 public:
  using RowVec = Eigen::Matrix<double, Rows, 1>;
  using Square = Eigen::Matrix<double, Rows, Rows>;

  LawSystem(int m, int nv);

  // The law's velocity from J and e: (10) qdot = J^T (J J^T + lambda2 I)^-1 e,
  // (9) qdot = J^T e.
  void qdot(LawKind law, double lambda2, Vec& dq);

  Eigen::Matrix<double, Rows, Eigen::Dynamic> J;  // task Jacobian (m, nv)
  RowVec e;                                       // task error (m)

 private:
  void solve_small();     // y = A^-1 e
  bool cholesky_solve();  // y = A^-1 e when A is positive definite

  RowVec y_, tmp_;
  Square A_;
  Square L_;  // the Cholesky factor of A_ (lower triangle)
  Eigen::JacobiSVD<Square> svd_;
};

class Solver {
 public:
  // `model` must outlive the solver; the solver owns its own pinocchio::Data.
  // `reference` (nq): the robot's reference configuration, where a solve
  // given no q0 starts (the caller's business: see reference()).
  Solver(const pinocchio::Model& model, const SolveTask& task, const SolveSettings& settings,
         const Vec& reference);

  // Begin a new solve (forgetting the last one): target p_d, R_d (each unused
  // where the task has no such rows), clipping bounds from the model's limits
  // as they are now, and one attempt from q0 (nq entries). Returns false,
  // having run nothing, when an entry of the target or of q0 is not finite;
  // else success().
  bool start(const Vec3& position, const Mat3& rotation, const Eigen::Ref<const Vec>& q0);

  // Continue the solve: one attempt from each row of `starts` (nq columns) in
  // turn, until one converges. Returns success().
  bool run(const Mat& starts);

  const Vec& reference() const { return reference_; }

  // The converged configuration, else the best attempt's (least pos + rot).
  const Vec& q() const { return success_ ? q_ : best_q_; }
  bool success() const { return success_; }
  int iterations() const { return iterations_; }  // over all attempts
  int attempts() const { return attempts_; }
  double position_error() const { return success_ ? final_pos_ : best_pos_; }     // [m]
  double orientation_error() const { return success_ ? final_rot_ : best_rot_; }  // [rad]

 private:
  struct Attempt {
    bool converged;
    int iterations;
    double position_error, orientation_error;
  };

  Attempt attempt();
  void attempt_from_q();
  void error(const Vec& q);
  void pose_jacobian();
  void world_errors(double& pos, double& rot) const;
  void step(double err2);

  const pinocchio::Model& model_;
  ModelShape built_;  // the model's sizes when the solver was built
  pinocchio::Data data_;
  SolveTask task_;
  SolveSettings s_;
  bool full_pose_, has_position_, has_orientation_;
  int m_;
  Vec reference_;

  // The target and bounds of the solve (start()).
  Vec3 position_ = Vec3::Zero();      // p_d
  Mat3 rotation_ = Mat3::Identity();  // R_d
  pinocchio::SE3 target_se3_;         // oMd, for a full pose
  Vec lower_, upper_;  // clipping bounds per q entry, -inf / +inf where not clipped
  bool clip_ = false;

  // Workspaces.
  Vec q_, q_next_, dq_;
  Eigen::Matrix<double, 6, 1> e6_;
  LawSystem<6> pose_;                  // e and J of a full pose
  LawSystem<Eigen::Dynamic> masked_;   // e and J of a masked task (empty for a full pose)
  pinocchio::Data::Matrix6x J6_;  // the frame Jacobian (LOCAL or LOCAL_WORLD_ALIGNED)
  Eigen::Matrix<double, 6, 6> Jlog_;
  Mat3 R_err_;
  double pos_ = 0.0, rot_ = 0.0;  // error norms at the last error() [m], [rad]

  // The solve so far.
  bool success_ = false;
  int iterations_ = 0, attempts_ = 0;
  double final_pos_ = 0.0, final_rot_ = 0.0;  // world-frame errors at the converged q
  double best_total_;                         // least pos + rot of a failed attempt
  Vec best_q_;
  double best_pos_, best_rot_;
};

}  // namespace clik
