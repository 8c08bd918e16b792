// Joint values as a goal: see tasks/posture_goal.hpp.
#include "tasks/posture_goal.hpp"

#include <cmath>

#include <nanobind/stl/vector.h>

namespace nb = nanobind;

namespace clik {

PostureGoalRun::PostureGoalRun(const pinocchio::Model& model, const PostureGoal& goal)
    : idx_q_(goal.idx_q), idx_v_(goal.idx_v), continuous_(goal.continuous.begin(),
                                                          goal.continuous.end()) {
  const size_t n = idx_q_.size();
  if (n == 0 || idx_v_.size() != n || continuous_.size() != n) {
    throw std::invalid_argument("PostureGoal: idx_q, idx_v and continuous, one entry per joint (at least one)");
  }
  for (size_t i = 0; i < n; ++i) {
    const int width = continuous_[i] ? 2 : 1;
    if (idx_q_[i] < 0 || idx_q_[i] + width > model.nq) {
      throw std::invalid_argument("PostureGoal: idx_q, configuration indices of the model (continuous: two)");
    }
    if (idx_v_[i] < 0 || idx_v_[i] >= model.nv) {
      throw std::invalid_argument("PostureGoal: idx_v, velocity indices of the model");
    }
  }
}

void PostureGoalRun::write(const GoalContext& c, const double* ref, const double* ff,
                           ExtendedTask& ext, int row0) {
  for (int i = 0; i < rows(); ++i) {
    const int iq = idx_q_[i];
    const double e = continuous_[i]
                         ? wrap_angle(ref[i] - std::atan2(c.q[iq + 1], c.q[iq]))
                         : ref[i] - c.q[iq];
    ext.e[row0 + i] = e;
    ext.J(row0 + i, idx_v_[i]) = 1.0;  // the row's other entries: zero from the start
    ext.ff[row0 + i] = ff[i];
  }
}

void PostureGoalRun::norms(const ExtendedTask& ext, int row0, double& first,
                           double& second) const {
  first = ext.e.segment(row0, rows()).norm();
  second = 0.0;
}

void PostureGoalRun::columns(const pinocchio::Model&, int* lo, int* hi) const {
  for (int i = 0; i < rows(); ++i) {
    lo[i] = idx_v_[i];
    hi[i] = idx_v_[i] + 1;
  }
}

void PostureGoal::bind(nb::module_& m) {
  nb::class_<PostureGoal>(m, "PostureGoal",
                          "Joint angles of 1-DoF joints: idx_q, idx_v, continuous per joint.")
      .def(
          "__init__",
          [](PostureGoal* self, std::vector<int> idx_q, std::vector<int> idx_v,
             std::vector<bool> continuous) {
            new (self) PostureGoal{std::move(idx_q), std::move(idx_v), std::move(continuous)};
          },
          nb::arg("idx_q"), nb::arg("idx_v"), nb::arg("continuous"))
      .def_ro("idx_q", &PostureGoal::idx_q)
      .def_ro("idx_v", &PostureGoal::idx_v);
}

}  // namespace clik
