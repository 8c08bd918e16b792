// An axis of a frame that points at a point, as a goal (mirrors clik/tasks/gaze_task.py,
// the specification: the same formulas; docs/method.md, "Several tasks"; the protocol:
// tasks/goal_kind.hpp). Two rows: the rotation vector turning the axis onto the direction
// to the point, in the gaze axes. The kind in one header: its config, its run and its
// binding.
#pragma once

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/spatial/skew.hpp>

#include "tasks/goal_kind.hpp"

namespace clik {

class GazeGoalRun;

// `_engine.GazeGoal`: the frame and its axis (in its own axes, unit). Reference: the point
// g (3) [m] in the world; feed-forward: its velocity (3) [m/s] (the rows' depend on q).
struct GazeGoal {
  using Run = GazeGoalRun;
  // Below it, the limits of theta / s (gaze_task.py's; bound as
  // `_engine.GazeGoal.SMALL_SINE`, checked against it by the kinds' tests).
  static constexpr double SMALL_SINE = 1e-8;
  int frame = 0;
  Vec3 axis = Vec3::UnitZ();
  static void bind(nanobind::module_& m);
};

// The error e (2) of a direction w in the gaze axes and E = de/dw (2 x 3)
// (clik/tasks/gaze_task.py's gaze_error).
inline void gaze_error(const Vec3& w, Eigen::Vector2d& e, Eigen::Matrix<double, 2, 3>& E) {
  constexpr double SMALL_SINE = GazeGoal::SMALL_SINE;
  double wx = w[0];
  const double wy = w[1], wz = w[2];
  double s = std::hypot(wx, wy);
  if (s < SMALL_SINE && wz < 0.0) {  // pointing away: turn about one axis
    wx = SMALL_SINE;
    s = SMALL_SINE;
  }
  const double r2 = wx * wx + wy * wy + wz * wz;
  double f, g;
  if (s < SMALL_SINE) {  // the limits of theta / s and of its derivative's factor
    f = 1.0 / wz;
    g = -2.0 / (3.0 * wz * wz * wz);
  } else {
    f = std::atan2(s, wz) / s;
    g = (wz / r2 - f) / (s * s);
  }
  e << -f * wy, f * wx;
  E << -wy * wx * g, -(wy * wy * g + f), wy / r2,  //
      wx * wx * g + f, wx * wy * g, -wx / r2;
}

class GazeGoalRun {
 public:
  GazeGoalRun(const pinocchio::Model& model, const GazeGoal& goal)
      : frame_(goal.frame), J6_(6, model.nv), T_(3, model.nv) {
    check_frame(model, goal.frame, "GazeGoal: frame");
    const double n = goal.axis.norm();
    if (!(goal.axis.allFinite() && n > 1e-9)) {
      throw std::invalid_argument("GazeGoal: axis, a non-zero finite 3-vector");
    }
    S_ = Eigen::Quaterniond::FromTwoVectors(goal.axis / n, Vec3::UnitZ()).toRotationMatrix();
    J6_.setZero();
    T_.setZero();
  }
  int rows() const { return 2; }
  int ref_size() const { return 3; }
  int ff_size() const { return 3; }

  // v = R^T (g - o), d = v / |v|, (e, E) of w = S d; J = -E S P T / |v|,
  // xdot_d = E S P R^T gdot / |v| (docs/method.md).
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0) {
    constexpr auto LWA = pinocchio::LOCAL_WORLD_ALIGNED;
    const auto f = static_cast<pinocchio::FrameIndex>(frame_);
    const pinocchio::SE3& oMf = c.data.oMf[f];
    const Mat3 Rt = oMf.rotation().transpose();
    const Vec3 v = Rt * (Eigen::Map<const Vec3>(ref) - oMf.translation());
    const double n = std::max(v.norm(), 1e-12);  // the point at the origin: no direction
    const Vec3 d = v / n;
    Eigen::Vector2d e;
    Eigen::Matrix<double, 2, 3> E;
    gaze_error(S_ * d, e, E);
    const Eigen::Matrix<double, 2, 3> A = E * S_ * (Mat3::Identity() - d * d.transpose()) / n;
    pinocchio::getFrameJacobian(c.model, c.data, f, LWA, J6_);
    T_.noalias() = pinocchio::skew(v) * Rt * J6_.bottomRows<3>();
    T_.noalias() -= Rt * J6_.topRows<3>();
    ext.J.middleRows<2>(row0).noalias() = -A * T_;
    ext.e.segment<2>(row0) = e;
    ext.ff.segment<2>(row0).noalias() = A * (Rt * Eigen::Map<const Vec3>(ff));
  }

  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const {
    first = ext.e.segment<2>(row0).norm();
    second = 0.0;
  }

  void columns(const pinocchio::Model& model, int* lo, int* hi) const {
    int a = model.nv, b = 0;
    frame_columns(model, frame_, a, b);
    if (a >= b) a = model.nv, b = 0;
    lo[0] = lo[1] = a;
    hi[0] = hi[1] = b;
  }

  TargetReader target() const { return FrameTarget{true, false, {0, 1, 2}, false}; }
  void frames(std::vector<int>& out) const { out.push_back(frame_); }
  bool needs_com() const { return false; }

 private:
  int frame_;
  Mat3 S_;  // the fixed rotation taking the axis to e_z
  Eigen::Matrix<double, 6, Eigen::Dynamic> J6_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> T_;  // [v]x R^T J_w - R^T J_v
};

inline void GazeGoal::bind(nanobind::module_& m) {
  namespace nb = nanobind;
  nb::class_<GazeGoal>(m, "GazeGoal", "The axis (in the frame) of frame points at a point.")
      .def(
          "__init__",
          [](GazeGoal* self, int frame, const Vec3& axis) { new (self) GazeGoal{frame, axis}; },
          nb::kw_only(), nb::arg("frame"), nb::arg("axis"))
      .def_ro("frame", &GazeGoal::frame)
      .def_prop_ro("axis", [](const GazeGoal& s) { return s.axis; })
      .attr("SMALL_SINE") = SMALL_SINE;
}

}  // namespace clik
