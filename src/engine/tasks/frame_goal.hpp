// A frame's pose as a goal, in the world or relative to another frame (mirrors
// clik/tasks/task.py and clik/tasks/relative_task.py; the protocol: tasks/goal_kind.hpp).
#pragma once

#include <vector>

#include <nanobind/nanobind.h>

#include "tasks/goal_kind.hpp"

namespace clik {

class FrameGoalRun;

// `_engine.FrameGoal`: rows among 0..5 = (x, y, z, rx, ry, rz); relative_to -1: the world.
// Reference per sample: p (3), then R row-major (9) (relative: the pose of the frame in
// relative_to's); feed-forward: its rows'.
struct FrameGoal {
  using Run = FrameGoalRun;
  int frame = 0;
  std::vector<int> rows;
  int relative_to = -1;
  static void bind(nanobind::module_& m);
};

class FrameGoalRun {
 public:
  FrameGoalRun(const pinocchio::Model& model, const FrameGoal& goal);
  int rows() const { return static_cast<int>(rows_.size()); }
  int ref_size() const { return 12; }
  int ff_size() const { return rows(); }
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0);
  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;
  TargetReader target() const;
  void frames(std::vector<int>& out) const;
  bool needs_com() const { return false; }

 private:
  int frame_, relative_to_;
  std::vector<int> rows_;
  Eigen::Matrix<double, 6, Eigen::Dynamic> Ja_, Jb_;
  Eigen::Matrix<double, 6, 1> e6_;
};

}  // namespace clik
