// The centre of mass as a goal (mirrors clik/tasks/com_task.py; the protocol:
// tasks/goal_kind.hpp).
#pragma once

#include <vector>

#include <nanobind/nanobind.h>

#include "tasks/goal_kind.hpp"

namespace clik {

class ComGoalRun;

// The centre of mass c (data.com[0]) and its Jacobian (data.Jcom, 3 x nv, world axes)
// from the joint placements and world Jacobians computeJointJacobians leaves in data:
// joint j's columns are (m_j J_v + J_w x s_j) / M, m_j and s_j its subtree's mass and
// mass-weighted centre (data.mass[j], data.com[j] m_j). pinocchio::jacobianCenterOfMass's
// figures without its second forward pass.
void com_jacobian(const pinocchio::Model& model, pinocchio::Data& data);

// `_engine.ComGoal`: rows among 0..2. Reference: c_d (3) [m]; feed-forward: its rows'.
struct ComGoal {
  using Run = ComGoalRun;
  std::vector<int> rows;
  static void bind(nanobind::module_& m);
};

class ComGoalRun {
 public:
  ComGoalRun(const pinocchio::Model& model, const ComGoal& goal);
  int rows() const { return static_cast<int>(rows_.size()); }
  int ref_size() const { return 3; }
  int ff_size() const { return rows(); }
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0);
  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;
  TargetReader target() const { return FrameTarget{true, false, rows_, false}; }
  void frames(std::vector<int>&) const {}
  bool needs_com() const { return true; }

 private:
  std::vector<int> rows_;
};

}  // namespace clik
