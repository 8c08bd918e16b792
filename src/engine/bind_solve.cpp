// Python entry point of solve mode: clik.solve(..., engine="compiled") keeps
// one Solver per task and settings; each solve start()s it on the target from
// q0, then, if that attempt fails, run()s it from the restart configurations
// drawn with the seeded generator.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "model_bridge.hpp"
#include "solve.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

LawKind solve_law(const std::string& law) {
  if (law == "pseudoinverse") return LawKind::pseudoinverse;
  if (law == "transpose") return LawKind::transpose;
  throw std::invalid_argument("law: expected 'pseudoinverse' or 'transpose' in solve mode, got '" +
                              law + "'");
}

// (success, q, iterations, attempts, position_error, orientation_error) of the solve so far.
nb::tuple outcome(const Solver& self) {
  return nb::make_tuple(self.success(), Vec(self.q()), self.iterations(), self.attempts(),
                        self.position_error(), self.orientation_error());
}

}  // namespace

void bind_solve(nb::module_& m) {
  nb::class_<Solver>(m, "Solver",
                     "One single-pose solve (clik/solve_mode.py): damped Levenberg-Marquardt on "
                     "log6 for a full pose, on the masked world-aligned error otherwise.")
      .def(
          "__init__",
          [](Solver* self, nb::handle model, std::size_t frame_id, const std::vector<int>& rows,
             const std::string& law, double step, double damping, double mu, double tolerance,
             double orientation_tolerance, int max_iterations) {
            SolveTask task;
            task.frame_id = frame_id;
            task.rows = rows;
            SolveSettings s;
            s.law = solve_law(law);
            s.step = step;
            s.damping = damping;
            s.mu = mu;
            s.tolerance = tolerance;
            s.orientation_tolerance = orientation_tolerance;
            s.max_iterations = max_iterations;
            new (self) Solver(borrow_model(model.ptr()), task, s);
          },
          nb::arg("model"), nb::arg("frame_id"), nb::arg("rows"), nb::kw_only(), nb::arg("law"),
          nb::arg("step"), nb::arg("damping"), nb::arg("mu"), nb::arg("tolerance"),
          nb::arg("orientation_tolerance"), nb::arg("max_iterations"),
          nb::keep_alive<1, 2>(),  // the pin.Model outlives the solver that borrows it
          "model: a pin.Model (borrowed, not copied; the solver has its own data); rows: the "
          "task's rows among (x, y, z, rx, ry, rz). One solver serves any number of solves.")
      .def(
          "start",
          [](Solver& self, const Vec3& position, const Mat3& rotation,
             const Vec& q0) -> nb::object {
            if (!self.start(position, rotation, q0)) return nb::none();
            return outcome(self);
          },
          nb::arg("position"), nb::arg("rotation"), nb::arg("q0"),
          "A new solve of the target p_d = position, R_d = rotation (placeholders where the "
          "task has no such rows), clipped to the model's limits as they are now: one attempt "
          "from q0 (nq,). Returns (success, q, iterations, attempts, position_error, "
          "orientation_error), or None, having run nothing, when an entry of position, "
          "rotation or q0 is not finite.")
      .def(
          "run",
          [](Solver& self, const Mat& starts) {
            self.run(starts);
            return outcome(self);
          },
          nb::arg("starts"),
          "Continue the solve: one attempt from each row of starts (k, nq) in turn until one "
          "converges. Returns the outcome so far, as start(); q the converged or else the best "
          "attempt's.");
}

}  // namespace clik
