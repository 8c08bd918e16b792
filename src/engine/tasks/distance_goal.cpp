// The distance between two frames' origins as a goal: see tasks/distance_goal.hpp.
#include "tasks/distance_goal.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <pinocchio/algorithm/frames.hpp>

namespace nb = nanobind;

namespace clik {

namespace {
constexpr auto LWA = pinocchio::LOCAL_WORLD_ALIGNED;
constexpr double MIN_DISTANCE = 1e-9;  // the row's direction u needs two apart origins [m]
}  // namespace

DistanceGoalRun::DistanceGoalRun(const pinocchio::Model& model, const DistanceGoal& goal)
    : a_(goal.frame), b_(goal.relative_to), Ja_(6, model.nv), Jb_(6, model.nv) {
  check_frame(model, goal.frame, "DistanceGoal: frame");
  check_frame(model, goal.relative_to, "DistanceGoal: relative_to");
  if (goal.frame == goal.relative_to) {
    throw std::invalid_argument("DistanceGoal: relative_to, a frame other than frame");
  }
  Ja_.setZero();
  Jb_.setZero();
}

// e = rho_d - |p_a - p_b|, J = u^T (J_v,a - J_v,b), the rate rho_dot_d as feed-forward.
void DistanceGoalRun::write(const GoalContext& c, const double* ref, const double* ff,
                            ExtendedTask& ext, int row0) {
  const auto fa = static_cast<pinocchio::FrameIndex>(a_);
  const auto fb = static_cast<pinocchio::FrameIndex>(b_);
  const Vec3 d = c.data.oMf[fa].translation() - c.data.oMf[fb].translation();
  const double rho = d.norm();
  pinocchio::getFrameJacobian(c.model, c.data, fa, LWA, Ja_);
  pinocchio::getFrameJacobian(c.model, c.data, fb, LWA, Jb_);
  const Vec3 u = d / std::max(rho, MIN_DISTANCE);
  ext.e[row0] = ref[0] - rho;
  ext.J.row(row0).noalias() = u.transpose() * (Ja_.topRows<3>() - Jb_.topRows<3>());
  ext.ff[row0] = ff[0];
}

void DistanceGoalRun::norms(const ExtendedTask& ext, int row0, double& first,
                            double& second) const {
  first = std::abs(ext.e[row0]);
  second = 0.0;
}

void DistanceGoalRun::columns(const pinocchio::Model& model, int* lo, int* hi) const {
  int a = model.nv, b = 0;
  frame_columns(model, a_, a, b);
  frame_columns(model, b_, a, b);
  if (a >= b) a = model.nv, b = 0;
  lo[0] = a;
  hi[0] = b;
}

void DistanceGoalRun::frames(std::vector<int>& out) const {
  out.push_back(a_);
  out.push_back(b_);
}

void DistanceGoal::bind(nb::module_& m) {
  nb::class_<DistanceGoal>(m, "DistanceGoal",
                           "The distance between the origins of frame and relative_to [m].")
      .def(
          "__init__",
          [](DistanceGoal* self, int frame, int relative_to) {
            new (self) DistanceGoal{frame, relative_to};
          },
          nb::kw_only(), nb::arg("frame"), nb::arg("relative_to"))
      .def_ro("frame", &DistanceGoal::frame)
      .def_ro("relative_to", &DistanceGoal::relative_to);
}

}  // namespace clik
