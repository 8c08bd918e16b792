// The centre of mass as a goal: see tasks/com_goal.hpp.
#include "tasks/com_goal.hpp"

#include <algorithm>

#include <nanobind/stl/vector.h>

namespace nb = nanobind;

namespace clik {

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
