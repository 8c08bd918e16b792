// The distance between the origins of two frames as a goal (mirrors
// clik/tasks/distance_task.py; docs/method.md, "Several tasks"; the protocol:
// tasks/goal_kind.hpp). One row: e = rho_d - rho, J = u^T (J_v,a - J_v,b).
#pragma once

#include <vector>

#include <nanobind/nanobind.h>

#include "tasks/goal_kind.hpp"

namespace clik {

class DistanceGoalRun;

// `_engine.DistanceGoal`: frames A and B. Reference: rho_d (1) [m]; feed-forward: its rate.
struct DistanceGoal {
  using Run = DistanceGoalRun;
  int frame = 0, relative_to = 0;
  static void bind(nanobind::module_& m);
};

class DistanceGoalRun {
 public:
  DistanceGoalRun(const pinocchio::Model& model, const DistanceGoal& goal);
  int rows() const { return 1; }
  int ref_size() const { return 1; }
  int ff_size() const { return 1; }
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0);
  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;
  TargetReader target() const { return ValuesTarget{1, "distance", "m", "rate", "m/s"}; }
  void frames(std::vector<int>& out) const;
  bool needs_com() const { return false; }

 private:
  int a_, b_;
  Eigen::Matrix<double, 6, Eigen::Dynamic> Ja_, Jb_;
};

}  // namespace clik
