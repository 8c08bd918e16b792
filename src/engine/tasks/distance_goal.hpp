// The distance between the origins of two frames as a goal (mirrors
// clik/tasks/distance_task.py; docs/method.md, "Several tasks"; the protocol:
// tasks/goal_kind.hpp). One row: e = rho_d - rho, J = u^T (J_v,a - J_v,b). The kind in
// one header: its config, its run and its binding.
#pragma once

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <nanobind/nanobind.h>
#include <pinocchio/algorithm/frames.hpp>

#include "tasks/goal_kind.hpp"

namespace clik {

class DistanceGoalRun;

// `_engine.DistanceGoal`: frames A and B. Reference: rho_d (1) [m]; feed-forward: its rate.
struct DistanceGoal {
  using Run = DistanceGoalRun;
  // The row's direction u needs two apart origins [m] (distance_task.py's; bound as
  // `_engine.DistanceGoal.MIN_DISTANCE`, checked against it by the kinds' tests).
  static constexpr double MIN_DISTANCE = 1e-9;
  int frame = 0, relative_to = 0;
  static void bind(nanobind::module_& m);
};

class DistanceGoalRun {
 public:
  DistanceGoalRun(const pinocchio::Model& model, const DistanceGoal& goal)
      : a_(goal.frame), b_(goal.relative_to), Ja_(6, model.nv), Jb_(6, model.nv) {
    check_frame(model, goal.frame, "DistanceGoal: frame");
    check_frame(model, goal.relative_to, "DistanceGoal: relative_to");
    if (goal.frame == goal.relative_to) {
      throw std::invalid_argument("DistanceGoal: relative_to, a frame other than frame");
    }
    Ja_.setZero();
    Jb_.setZero();
  }
  int rows() const { return 1; }
  int ref_size() const { return 1; }
  int ff_size() const { return 1; }

  // e = rho_d - |p_a - p_b|, J = u^T (J_v,a - J_v,b), the rate rho_dot_d as feed-forward.
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0) {
    constexpr auto LWA = pinocchio::LOCAL_WORLD_ALIGNED;
    const auto fa = static_cast<pinocchio::FrameIndex>(a_);
    const auto fb = static_cast<pinocchio::FrameIndex>(b_);
    const Vec3 d = c.data.oMf[fa].translation() - c.data.oMf[fb].translation();
    const double rho = d.norm();
    pinocchio::getFrameJacobian(c.model, c.data, fa, LWA, Ja_);
    pinocchio::getFrameJacobian(c.model, c.data, fb, LWA, Jb_);
    const Vec3 u = d / std::max(rho, DistanceGoal::MIN_DISTANCE);
    ext.e[row0] = ref[0] - rho;
    ext.J.row(row0).noalias() = u.transpose() * (Ja_.topRows<3>() - Jb_.topRows<3>());
    ext.ff[row0] = ff[0];
  }

  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const {
    first = std::abs(ext.e[row0]);
    second = 0.0;
  }

  void columns(const pinocchio::Model& model, int* lo, int* hi) const {
    int a = model.nv, b = 0;
    frame_columns(model, a_, a, b);
    frame_columns(model, b_, a, b);
    if (a >= b) a = model.nv, b = 0;
    lo[0] = a;
    hi[0] = b;
  }

  TargetReader target() const { return ValuesTarget{1, "distance", "m", "rate", "m/s"}; }
  void frames(std::vector<int>& out) const {
    out.push_back(a_);
    out.push_back(b_);
  }
  bool needs_com() const { return false; }

 private:
  int a_, b_;
  Eigen::Matrix<double, 6, Eigen::Dynamic> Ja_, Jb_;
};

inline void DistanceGoal::bind(nanobind::module_& m) {
  namespace nb = nanobind;
  nb::class_<DistanceGoal>(m, "DistanceGoal",
                           "The distance between the origins of frame and relative_to [m].")
      .def(
          "__init__",
          [](DistanceGoal* self, int frame, int relative_to) {
            new (self) DistanceGoal{frame, relative_to};
          },
          nb::kw_only(), nb::arg("frame"), nb::arg("relative_to"))
      .def_ro("frame", &DistanceGoal::frame)
      .def_ro("relative_to", &DistanceGoal::relative_to)
      .attr("MIN_DISTANCE") = MIN_DISTANCE;
}

}  // namespace clik
