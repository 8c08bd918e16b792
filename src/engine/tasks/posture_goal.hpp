// Joint values as a goal (mirrors clik/tasks/posture_task.py; the protocol:
// tasks/goal_kind.hpp).
#pragma once

#include <vector>

#include <nanobind/nanobind.h>

#include "tasks/goal_kind.hpp"

namespace clik {

class PostureGoalRun;

// `_engine.PostureGoal`: 1-DoF joints, q[idx_q] (continuous joints: the angle of (cos, sin)
// at idx_q, idx_q + 1), velocity columns idx_v. Reference and feed-forward: one double per
// joint [rad or m].
struct PostureGoal {
  using Run = PostureGoalRun;
  std::vector<int> idx_q, idx_v;
  std::vector<bool> continuous;
  static void bind(nanobind::module_& m);
};

class PostureGoalRun {
 public:
  PostureGoalRun(const pinocchio::Model& model, const PostureGoal& goal);
  int rows() const { return static_cast<int>(idx_q_.size()); }
  int ref_size() const { return rows(); }
  int ff_size() const { return rows(); }
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0);
  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;
  TargetReader target() const { return ValuesTarget{rows()}; }
  void frames(std::vector<int>&) const {}
  bool needs_com() const { return false; }

 private:
  std::vector<int> idx_q_, idx_v_;
  std::vector<char> continuous_;
};

}  // namespace clik
