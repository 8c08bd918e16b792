// The centre of mass as a goal: see tasks/com_goal.hpp.
#include "tasks/com_goal.hpp"

#include <algorithm>

#include <nanobind/stl/vector.h>

namespace nb = nanobind;

namespace clik {

void com_jacobian(const pinocchio::Model& model, pinocchio::Data& data) {
  const int nj = static_cast<int>(model.njoints);
  data.mass[0] = 0.0;
  data.com[0].setZero();
  for (int i = 1; i < nj; ++i) {
    const auto& inertia = model.inertias[static_cast<std::size_t>(i)];
    data.mass[i] = inertia.mass();
    data.com[i].noalias() = inertia.mass() * data.oMi[i].act(inertia.lever());
  }
  for (int i = nj - 1; i > 0; --i) {  // a parent's index is below its children's
    const auto p = model.parents[static_cast<std::size_t>(i)];
    data.mass[p] += data.mass[i];
    data.com[p] += data.com[i];
  }
  const double total = data.mass[0];
  for (int i = 1; i < nj; ++i) {
    const auto& joint = model.joints[static_cast<std::size_t>(i)];
    const Vec3& s = data.com[i];
    const double m = data.mass[i];
    for (int k = joint.idx_v(); k < joint.idx_v() + joint.nv(); ++k) {
      const auto column = data.J.col(k);
      data.Jcom.col(k) = (m * column.head<3>() + column.tail<3>().cross(s)) / total;
    }
  }
  for (int i = 0; i < nj; ++i) {  // each subtree's centre, as pinocchio leaves it
    if (data.mass[i] > 0.0) data.com[i] /= data.mass[i];
  }
}

ComGoalRun::ComGoalRun(const pinocchio::Model&, const ComGoal& goal) : rows_(goal.rows) {
  check_rows(goal.rows, 3, "ComGoal");
}

void ComGoalRun::write(const GoalContext& c, const double* ref, const double* ff,
                       ExtendedTask& ext, int row0) {
  const Vec3& com = c.data.com[0];
  for (int i = 0; i < rows(); ++i) {
    const int row = rows_[i];
    ext.e[row0 + i] = ref[row] - com[row];
    ext.J.row(row0 + i) = c.data.Jcom.row(row);
    ext.ff[row0 + i] = ff[i];
  }
}

void ComGoalRun::norms(const ExtendedTask& ext, int row0, double& first, double& second) const {
  first = ext.e.segment(row0, rows()).norm();
  second = 0.0;
}

void ComGoalRun::columns(const pinocchio::Model& model, int* lo, int* hi) const {
  std::fill(lo, lo + rows(), 0);
  std::fill(hi, hi + rows(), model.nv);
}

void ComGoal::bind(nb::module_& m) {
  nb::class_<ComGoal>(m, "ComGoal", "The centre of mass, rows among 0..2.")
      .def(
          "__init__",
          [](ComGoal* self, std::vector<int> rows) { new (self) ComGoal{std::move(rows)}; },
          nb::arg("rows"))
      .def_ro("rows", &ComGoal::rows);
}

}  // namespace clik
