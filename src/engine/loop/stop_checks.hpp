// When a run stops early: divergence, instability, deadlock and stall, checked
// every sample (mirrors clik/loop/stop_checks.py, whose module docstring explains
// each condition). The checks return what happened and its numbers; the
// reason in words is written once, in Python (clik/loop/stop_checks.py).
#pragma once

#include <Eigen/Eigenvalues>

#include "tasks/extended_task.hpp"
#include "types.hpp"

namespace clik {

constexpr double BLOCKED_FRACTION = 0.5;  // law (10): the task is blocked above this
constexpr int STABILITY_EVERY = 10;       // samples between stability rechecks, (9) and (8)

struct StopSettings {
  double deadlock_window = 0.1;
  double deadlock_ratio = 1e-4;
  double deadlock_error = 1e-3;
  double max_joint_step = 1.0;
  double stall_window = 0.5;
  double stall_progress = 0.01;
};

// Why a run stopped, with the numbers its reason cites.
enum class Stop { none, non_finite, joint_step, unstable, deadlock, stall };

class StopChecks {
 public:
  StopChecks(const StopSettings& settings, LawKind law, double dt, int rows);

  // The step just computed is non-finite or too large; sets jump.
  Stop divergence(const Vec& qdot, double err);
  // The gains break explicit Euler's bound and the error has grown; sets margin.
  Stop instability(long k, const ExtendedTask& ext, int r, double err);
  // Remark 2 held for deadlock_window.
  bool deadlock(const ExtendedTask& ext, int r, double err, double blocked);
  // With the reference at rest, the error fell by too little over stall_window.
  bool stall(long k, double err, bool at_rest);

  double jump = 0.0;          // the last joint step max |qdot| dt [rad or m]
  double margin = 0.0;        // the last stability margin
  double worst_margin = 0.0;  // the largest over the run

 private:
  double stability_margin(const ExtendedTask& ext, int r);

  StopSettings s_;
  LawKind law_;
  double dt_;
  long window_, stall_steps_;
  long stuck_ = 0;
  long stall_k_ = -1;
  double stall_err_ = 0.0;
  Eigen::MatrixXd S_, A_;
  Vec Ke_, force_;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig_;
};

}  // namespace clik
