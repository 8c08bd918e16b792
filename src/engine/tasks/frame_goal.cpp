// A frame's pose as a goal: see tasks/frame_goal.hpp.
#include "tasks/frame_goal.hpp"

#include <algorithm>
#include <string>

#include <nanobind/stl/vector.h>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/spatial/explog.hpp>
#include <pinocchio/spatial/skew.hpp>

namespace nb = nanobind;

namespace clik {

namespace {
constexpr auto LWA = pinocchio::LOCAL_WORLD_ALIGNED;
using RowMat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
}  // namespace

FrameGoalRun::FrameGoalRun(const pinocchio::Model& model, const FrameGoal& goal)
    : frame_(goal.frame), relative_to_(goal.relative_to), rows_(goal.rows),
      Ja_(6, model.nv), Jb_(6, model.nv), e6_(Eigen::Matrix<double, 6, 1>::Zero()) {
  check_frame(model, goal.frame, "FrameGoal: frame");
  if (goal.relative_to != -1) check_frame(model, goal.relative_to, "FrameGoal: relative_to");
  if (goal.relative_to == goal.frame) {
    throw std::invalid_argument(
        "FrameGoal: relative_to, -1 (the world) or another frame index of the model");
  }
  check_rows(goal.rows, 6, "FrameGoal");
  Ja_.setZero();
  Jb_.setZero();
}

void FrameGoalRun::write(const GoalContext& c, const double* ref, const double* ff,
                         ExtendedTask& ext, int row0) {
  const auto fa = static_cast<pinocchio::FrameIndex>(frame_);
  const pinocchio::SE3& oMa = c.data.oMf[fa];
  const Eigen::Map<const Vec3> p_d(ref);
  const Eigen::Map<const RowMat3> R_d(ref + 3);
  // getFrameJacobian writes the frame's support columns, the same at every sample: the
  // others stay zero unless the relative form below wrote them
  if (relative_to_ >= 0) Ja_.setZero();
  pinocchio::getFrameJacobian(c.model, c.data, fa, LWA, Ja_);
  const Eigen::Matrix<double, 6, Eigen::Dynamic>* J = &Ja_;
  if (relative_to_ < 0) {
    e6_.head<3>() = p_d - oMa.translation();
    e6_.tail<3>() = pinocchio::log3((R_d * oMa.rotation().transpose()).eval());
  } else {
    // bMa = oMb^-1 oMa: p = R_b^T (p_a - p_b), R = R_b^T R_a; its Jacobian in B's axes.
    const auto fb = static_cast<pinocchio::FrameIndex>(relative_to_);
    const pinocchio::SE3& oMb = c.data.oMf[fb];
    const Mat3& Rb = oMb.rotation();
    const Vec3 d = oMa.translation() - oMb.translation();
    const Vec3 p = Rb.transpose() * d;
    const Mat3 R = Rb.transpose() * oMa.rotation();
    e6_.head<3>() = p_d - p;
    e6_.tail<3>() = pinocchio::log3((R_d * R.transpose()).eval());
    Jb_.setZero();
    pinocchio::getFrameJacobian(c.model, c.data, fb, LWA, Jb_);
    // J_lin = R_b^T (J_a_lin - J_b_lin + skew(p_a - p_b) J_b_ang), J_ang = R_b^T (J_a_ang - J_b_ang)
    Ja_.topRows<3>() -= Jb_.topRows<3>();
    Ja_.topRows<3>().noalias() += pinocchio::skew(d) * Jb_.bottomRows<3>();
    Ja_.bottomRows<3>() -= Jb_.bottomRows<3>();
    Jb_.topRows<3>().noalias() = Rb.transpose() * Ja_.topRows<3>();
    Jb_.bottomRows<3>().noalias() = Rb.transpose() * Ja_.bottomRows<3>();
    J = &Jb_;
  }
  for (int i = 0; i < rows(); ++i) {
    const int row = rows_[i];
    ext.e[row0 + i] = e6_[row];
    ext.J.row(row0 + i) = J->row(row);
    ext.ff[row0 + i] = ff[i];
  }
}

void FrameGoalRun::norms(const ExtendedTask& ext, int row0, double& first, double& second) const {
  double p2 = 0.0, r2 = 0.0;
  bool pos = false;
  for (int i = 0; i < rows(); ++i) {
    const double e = ext.e[row0 + i];
    if (rows_[i] < 3) {
      p2 += e * e;
      pos = true;
    } else {
      r2 += e * e;
    }
  }
  second = std::sqrt(r2);
  first = pos ? std::sqrt(p2) : second;
}

void FrameGoalRun::columns(const pinocchio::Model& model, int* lo, int* hi) const {
  int a = model.nv, b = 0;
  frame_columns(model, frame_, a, b);
  if (relative_to_ >= 0) frame_columns(model, relative_to_, a, b);
  if (a >= b) a = model.nv, b = 0;
  std::fill(lo, lo + rows(), a);
  std::fill(hi, hi + rows(), b);
}

TargetReader FrameGoalRun::target() const {
  const bool pos = std::any_of(rows_.begin(), rows_.end(), [](int r) { return r < 3; });
  const bool rot = std::any_of(rows_.begin(), rows_.end(), [](int r) { return r >= 3; });
  return FrameTarget{pos, rot, rows_, true};
}

void FrameGoalRun::frames(std::vector<int>& out) const {
  out.push_back(frame_);
  if (relative_to_ >= 0) out.push_back(relative_to_);
}

void FrameGoal::bind(nb::module_& m) {
  nb::class_<FrameGoal>(m, "FrameGoal",
                        "A frame's pose goal: rows among 0..5, relative_to -1 (the world) or "
                        "a frame.")
      .def(
          "__init__",
          [](FrameGoal* self, int frame, std::vector<int> rows, int relative_to) {
            new (self) FrameGoal{frame, std::move(rows), relative_to};
          },
          nb::arg("frame"), nb::arg("rows"), nb::arg("relative_to") = -1)
      .def_ro("frame", &FrameGoal::frame)
      .def_ro("rows", &FrameGoal::rows)
      .def_ro("relative_to", &FrameGoal::relative_to);
}

}  // namespace clik
