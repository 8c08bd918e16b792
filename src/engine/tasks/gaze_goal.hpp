// An axis of a frame that points at a point, as a goal (mirrors clik/tasks/gaze_task.py;
// docs/method.md, "Several tasks"; the protocol: tasks/goal_kind.hpp). Two rows: the
// rotation vector turning the axis onto the direction to the point, in the gaze axes.
#pragma once

#include <vector>

#include <nanobind/nanobind.h>

#include "tasks/goal_kind.hpp"

namespace clik {

class GazeGoalRun;

// `_engine.GazeGoal`: the frame and its axis (in its own axes, unit). Reference: the point
// g (3) [m] in the world; feed-forward: its velocity (3) [m/s] (the rows' depend on q).
struct GazeGoal {
  using Run = GazeGoalRun;
  int frame = 0;
  Vec3 axis = Vec3::UnitZ();
  static void bind(nanobind::module_& m);
};

// The error e (2) of a direction w in the gaze axes and E = de/dw (2 x 3)
// (clik/tasks/gaze_task.py's gaze_error).
void gaze_error(const Vec3& w, Eigen::Vector2d& e, Eigen::Matrix<double, 2, 3>& E);

class GazeGoalRun {
 public:
  GazeGoalRun(const pinocchio::Model& model, const GazeGoal& goal);
  int rows() const { return 2; }
  int ref_size() const { return 3; }
  int ff_size() const { return 3; }
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0);
  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;
  TargetReader target() const { return FrameTarget{true, false, {0, 1, 2}, false}; }
  void frames(std::vector<int>& out) const { out.push_back(frame_); }
  bool needs_com() const { return false; }

 private:
  int frame_;
  Mat3 S_;  // the fixed rotation taking the axis to e_z
  Eigen::Matrix<double, 6, Eigen::Dynamic> J6_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> T_;  // [v]x R^T J_w - R^T J_v
};

}  // namespace clik
