// One tracking run in the engine: the per-sample loop of clik/loop/tracking.py
// (_Run.execute), whose Python form is the specification. Per sample:
//   1. kinematics: the frame's placement and Jacobian at q_k, eq. (3);
//   2. task error e = x_d - x, eq. (6), on the task's rows;
//   3. constraint rows (13)-(19) into the extended task (24)-(25);
//   4. the law, (9), (8) or (10), within the joint speed limits (S1)-(S3);
//   5. stop checks and limits crossed;
//   6. recording, then q_{k+1} = q_k (+) qdot_k dt.
// Python samples the reference in chunks and calls advance() per chunk;
// nothing is allocated per sample. An open run (Clock::open: a controller's session, no
// last sample, a ring record) is advanced one tick at a time, advance(k, k + 1), with the
// same per-sample code; a stop there is reported and the run goes on (see advance).
#pragma once

#include <memory>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "loop/laws.hpp"
#include "loop/objectives.hpp"
#include "loop/recording.hpp"
#include "loop/speed_step.hpp"
#include "loop/stop_checks.hpp"
#include "constraints/violations.hpp"
#include "tasks/extended_task.hpp"
#include "tasks/goals.hpp"
#include "types.hpp"

namespace clik {

class ConstraintRun;  // constraints/constraint_run.hpp

// The task: a frame, its kept rows of (x, y, z, rx, ry, rz), what it has
// (`_engine.TaskConfig`).
struct TaskConfig {
  int frame = 0;
  std::vector<int> rows;
  bool has_position = true;
  bool has_orientation = false;
};

// The law and the task's gains (`_engine.LawConfig`).
struct LawConfig {
  LawSettings settings;
  Vec K_task;       // every task row's gain [1/s] (m: the primary's rows, then the goals')
  int rows = 0;     // room of the extended task: the task's rows and the most constraint rows
  double alpha = 0; // the task's largest gain [1/s] (the constraint rows' default gains)
  SpeedBounds speed; // the joint speed limits the law keeps (empty: none)
  std::vector<int> levels;                 // end row of each level (empty: one, [m])
  std::vector<ObjectiveConfig> objectives; // eq. (5), law (10) only
};

using StopConfig = StopSettings;  // `_engine.StopConfig`

// Where a run is after advance().
struct Advance {
  long next = 0;        // the next sample to run (c1 when the chunk is done, k + 1 at a stop)
  Stop stop = Stop::none;
  long k = -1;          // the sample it stopped at
  int r = 0;            // rows of the extended task then
  double err = 0.0;     // task error then (the stop checks': with goals, the largest of the
                        // primary's and the first level's goals')
};

class TrackingRun {
 public:
  // Throws std::invalid_argument when the task, the gains, the rows or the joints do not
  // fit the model.
  // goals: the extra goals after the primary task (issue 24), in row order (level by level).
  // constraints: built with offset m (every task row) and the primary's rows (task_m).
  TrackingRun(const pinocchio::Model& model, const TaskConfig& task, const LawConfig& law,
              const StopConfig& stop, const Clock& t, const RecordBuffers& record,
              JointMonitorConfig joints, ConstraintRun* constraints,
              const std::vector<GoalConfig>& goals = {});

  // Runs samples [c0, c1) with the chunk's reference: P_d (n, 3) or null, R_d
  // (n, 3, 3) row-major or null, FF (n, m0), at_rest (n); with goals goal_ref (n, D) and
  // goal_ff (n, M) (D, M: the goals' reference doubles and rows). q is the state, updated.
  // An offline run returns at a stop, q_k unchanged. An open run returns at a stop with
  // next = k + 1 and goes on: after a deadlock or a stall q_{k+1} as usual (the controller
  // keeps going); after a divergence (non_finite, joint_step, unstable) q_k (it holds).
  Advance advance(long c0, long c1, const double* P_d, const double* R_d, const double* FF,
                  const bool* at_rest, Eigen::Ref<Vec> q, const double* goal_ref = nullptr,
                  const double* goal_ff = nullptr);

  // The task rows: the primary's (m0) and every row (m); the goals.
  int primary_rows() const { return m0_; }
  int task_rows() const { return m_; }
  const Goals& goals() const { return goals_; }
  // Each goal's (first, second) error norm: the largest over every sample, the last's (G, 2).
  const Mat& goal_max() const { return goal_max_; }
  const Mat& goal_last() const { return goal_norms_; }

  double max_error() const { return max_err_; }
  double last_error() const { return err_; }
  double last_orientation_error() const { return err_rot_; }  // the primary's rotation rows
  bool is_open() const { return t_.is_open(); }
  double time(long k) const { return t_[k]; }  // t_k [s]
  long steps() const { return steps_; }
  long kept() const { return rec_.kept(); }
  const ExtendedTask& extended() const { return ext_; }
  const TaskConfig& task() const { return task_; }
  const Vec& qdot() const { return qdot_; }
  const StopChecks& checks() const { return checks_; }
  const ViolationMonitor& monitor() const { return monitor_; }

 private:
  void kinematics(const Vec& q);
  void task_rows(const double* p_d, const double* R_d, const double* xdot_d);
  void error_norms(double& pos, double& rot) const;
  Stop stop(long k, double err, int r, double blocked, bool at_rest);
  void step(Vec& q);
  void observe_limits(double tk, const Vec& q);
  static const TaskConfig& checked(const pinocchio::Model& model, const TaskConfig& task,
                                   const LawConfig& law, const JointMonitorConfig& joints);
  static LevelPlan level_plan(const pinocchio::Model& model, const TaskConfig& task,
                              const LawConfig& law, const Goals& goals);

  const pinocchio::Model& model_;
  pinocchio::Data data_;
  TaskConfig task_;
  Goals goals_;
  int m0_, m_;
  LevelPlan plan_;
  double dt_;
  Clock t_;
  ExtendedTask ext_;
  Law law_;
  Objectives objectives_;
  SpeedStep speed_;
  StopChecks checks_;
  Recorder rec_;
  ViolationMonitor monitor_;
  ConstraintRun* crun_;
  Eigen::Matrix<double, 6, Eigen::Dynamic> J6_;
  Eigen::Matrix<double, 6, 1> e6_;
  Vec qdot_, dq_, qnext_, qv_;  // qv_: the state in advance()
  std::vector<int> pos_rows_, rot_rows_;
  int first_goals_ = 0;  // goals in the first level (their errors count in the stop checks)
  bool full_kinematics_ = false;
  Mat goal_norms_, goal_max_;  // (G, 2)
  double max_err_ = 0.0, err_ = 0.0, err_rot_ = 0.0;
  long steps_ = 0;
  bool started_ = false;
};

}  // namespace clik
