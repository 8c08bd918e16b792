// Python entry point of solve mode: clik.solve(..., engine="compiled") keeps
// one Solver per task and settings; each solve start()s it on the target from
// q0, then, if that attempt fails, run()s it from the restart configurations
// drawn with the seeded generator.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <boost/python/converter/from_python.hpp>
#include <boost/python/converter/registered.hpp>

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "model/model_bridge.hpp"
#include "solving/solve.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

LawKind solve_law(const std::string& law) {
  if (law == "pseudoinverse" || law == "transpose") return law_kind(law);
  throw std::invalid_argument("law: expected 'pseudoinverse' or 'transpose' in solve mode, got '" +
                              law + "'");
}

// The pinocchio::SE3 behind a `pin.SE3` Python object, read in place through
// Boost.Python's registry (the binding system of `pin`, as model_bridge reads
// the model); throws std::invalid_argument when `obj` is not one.
const pinocchio::SE3& borrow_se3(nb::handle obj) {
  namespace cv = boost::python::converter;
  void* se3 = cv::get_lvalue_from_python(obj.ptr(), cv::registered<pinocchio::SE3>::converters);
  if (se3 == nullptr) throw std::invalid_argument("target: expected a pin.SE3");
  return *static_cast<const pinocchio::SE3*>(se3);
}

// The solve so far: q written into `q` (the converged or else the best
// attempt's configuration), (success, iterations, attempts, position_error,
// orientation_error) returned. Writing into the caller's array spares the
// export of a new one (numpy.asarray on a DLPack/buffer object: ~1-2 us).
nb::tuple outcome(const Solver& self, nb::DRef<Vec> q) {
  if (q.size() != self.q().size()) throw std::invalid_argument("q: expected nq entries");
  q = self.q();
  return nb::make_tuple(self.success(), self.iterations(), self.attempts(),
                        self.position_error(), self.orientation_error());
}

// start()'s answer: the outcome, or None when it refused a value that is not finite.
nb::object started(const Solver& self, bool ran, nb::DRef<Vec> q) {
  return ran ? nb::object(outcome(self, q)) : nb::none();
}

}  // namespace

void bind_solve(nb::module_& m) {
  m.attr("STALL_PROGRESS") = STALL_PROGRESS;
  m.attr("STALL_ITERATIONS") = STALL_ITERATIONS;
  nb::class_<Solver>(m, "Solver",
                     "Single-pose solves of one task with one set of settings "
                     "(clik/solving/solve_problem.py): damped Levenberg-Marquardt on log6 for a full pose, "
                     "on the masked world-aligned error otherwise.")
      .def(
          "__init__",
          [](Solver* self, nb::handle model, std::size_t frame_id, const std::vector<int>& rows,
             const Vec& reference, const std::string& law, double step, double damping, double mu,
             double tolerance, double orientation_tolerance, int max_iterations) {
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
            new (self) Solver(borrow_model(model.ptr()), task, s, reference);
          },
          nb::arg("model"), nb::arg("frame_id"), nb::arg("rows"), nb::arg("reference"),
          nb::kw_only(), nb::arg("law"), nb::arg("step"), nb::arg("damping"), nb::arg("mu"),
          nb::arg("tolerance"), nb::arg("orientation_tolerance"), nb::arg("max_iterations"),
          nb::keep_alive<1, 2>(),  // the pin.Model outlives the solver that borrows it
          "model: a pin.Model (borrowed, not copied; the solver has its own data); rows: the "
          "task's rows among (x, y, z, rx, ry, rz); reference: where start_se3 starts without "
          "q0. One solver serves any number of solves, one at a time.")
      .def(
          "start",
          [](Solver& self, const Vec3& position, const Mat3& rotation, const Vec& q0,
             nb::DRef<Vec> q) { return started(self, self.start(position, rotation, q0), q); },
          nb::arg("position"), nb::arg("rotation"), nb::arg("q0"), nb::arg("q").noconvert(),
          "A new solve of the target p_d = position, R_d = rotation (placeholders where the "
          "task has no such rows), clipped to the model's limits as they are now: one attempt "
          "from q0 (nq,). Writes the configuration into q (nq,) and returns (success, "
          "iterations, attempts, position_error, orientation_error); or returns None, having "
          "run nothing, when an entry of position, rotation or q0 is not finite.")
      .def(
          "start_se3",
          [](Solver& self, nb::handle target, const std::optional<Vec>& q0, nb::DRef<Vec> q) {
            const pinocchio::SE3& oMd = borrow_se3(target);
            return started(
                self, self.start(oMd.translation(), oMd.rotation(), q0 ? *q0 : self.reference()),
                q);
          },
          nb::arg("target"), nb::arg("q0").none(), nb::arg("q").noconvert(),
          "start() with the target a pin.SE3 (read in place), from q0 or, when None, from the "
          "reference configuration.")
      .def(
          "run",
          [](Solver& self, const Mat& starts, nb::DRef<Vec> q) {
            self.run(starts);
            return outcome(self, q);
          },
          nb::arg("starts"), nb::arg("q").noconvert(),
          "Continue the solve: one attempt from each row of starts (k, nq) in turn until one "
          "converges. Writes q and returns the outcome so far, as start(); q the converged or "
          "else the best attempt's configuration.");
}

}  // namespace clik
