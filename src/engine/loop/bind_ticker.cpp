// The controller's ticks in the engine (`_engine.Ticker`, used by clik/control/ticks.py):
// one sample of an open run per call, `TrackingRun::advance(k, k + 1)`, and the tick's
// verdict (docs/method.md, "Online control"; the Python form: Controller._verdict and
// Controller._off_track in clik/control/controller.py). `step` reads a frame task's target
// directly (the fast path); `step_arrays` takes the references Python packed (any tasks).
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include "boundary.hpp"
#include "loop/py_tracking_run.hpp"
#include "loop/tick_input.hpp"
#include "model/model_bridge.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

enum Verdict : int { ok = 0, deadlock = 1, violated = 2, diverged = 3, off_track = 4 };

// The tolerance of the off_track verdict: position [m], orientation [rad], settling [s].
struct TickTolerance {
  double position, orientation, settling;
};

struct PyTicker {
  nb::object owner;  // the PyTrackingRun (kept alive)
  PyTrackingRun* run;
  const pinocchio::Model* model;  // the run's (its Python object kept alive by the run)
  WrittenArray<double> q;     // the controller's joints (nq), q_k in, q_{k+1} out
  WrittenArray<double> qdot;  // qdot_k (nv), out
  TickTolerance tol;
  TickInput input;
  long notes = 0;
  double wall = 0.0;  // time in the ticks [s]
  double above_since = std::numeric_limits<double>::quiet_NaN();
  Advance last;

  // The verdict of the sample just run at time tk (the worst that holds).
  int judge(double tk) {
    const TrackingRun& r = *run->run;
    const long seen = notes;
    notes = r.monitor().notes();
    if (last.stop == Stop::deadlock || last.stop == Stop::stall) return deadlock;
    if (last.stop != Stop::none) return diverged;
    if (notes != seen) return violated;
    const TaskConfig& task = r.task();
    const double limit = task.has_position ? tol.position : tol.orientation;
    bool above = !(r.last_error() <= limit);
    if (task.has_position && task.has_orientation) {
      above = above || !(r.last_orientation_error() <= tol.orientation);
    }
    if (!above) {
      above_since = std::numeric_limits<double>::quiet_NaN();
      return ok;
    }
    if (std::isnan(above_since)) above_since = tk;
    return tk - above_since > tol.settling ? off_track : ok;
  }

  // The model's sizes, unchanged since the run was built (compared without a lookup).
  void check_model() const {
    if (!(ModelShape::of(*model) == run->built)) {
      require_same_model(run->built, *model, "Controller.step");
    }
  }

  // After the sample k: the verdict, and (verdict, error, orientation error, events, t_k).
  nb::tuple ran(long k, Advance a, std::chrono::steady_clock::time_point start) {
    run->next = a.next;
    last = a;
    const TrackingRun& r = *run->run;
    Eigen::Map<Vec>(qdot.data(), static_cast<Eigen::Index>(qdot.shape(0))) = r.qdot();
    const int verdict = judge(r.time(k));
    const long events = run->constraints ? static_cast<long>(run->constraints->events().size()) : 0;
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return nb::make_tuple(verdict, r.last_error(), r.last_orientation_error(), events, r.time(k));
  }

  Eigen::Map<Vec> joints() { return {q.data(), static_cast<Eigen::Index>(q.shape(0))}; }
};

void make_ticker(PyTicker* self, nb::object owner, WrittenArray<double> q,
                 WrittenArray<double> qdot, double tol_position, double tol_orientation,
                 double settling_time) {
  PyTrackingRun& run = nb::cast<PyTrackingRun&>(owner);
  require(run.run->is_open(), "Ticker: an open TrackingRun (t None)");
  require(q.ndim() == 1 && static_cast<long>(q.shape(0)) == run.record.nq() &&
              qdot.ndim() == 1 && static_cast<long>(qdot.shape(0)) == run.record.nv(),
          "Ticker: q (nq,) and qdot (nv,), float64, C-contiguous");
  const pinocchio::Model& model = borrow_model(run.model.ptr());
  require_same_model(run.built, model, "Ticker");
  require(finite_positive(tol_position) && finite_positive(tol_orientation) &&
              finite_positive(settling_time),
          "Ticker: tolerance (position [m], orientation [rad]) and settling_time [s], > 0");
  new (self) PyTicker{owner, &run, &model, q, qdot, {tol_position, tol_orientation, settling_time},
                      TickInput(run.run->task())};
}

// The fast path: a frame task's target (16, 3 or 9 doubles) and velocity (6, 3 or none);
// None when they do not fit the task (Python then gives the error, naming the field).
std::optional<nb::tuple> step(PyTicker& self, In<double> target,
                              std::optional<In<double>> velocity) {
  PyTrackingRun& run = *self.run;
  self.check_model();
  if (run.run->goals().count() != 0) {  // no std::string built on the fast path
    throw std::invalid_argument("Ticker.step: one task (step_arrays for several)");
  }
  const long vn = velocity ? static_cast<long>(velocity->size()) : 0;
  if (!self.input.set(target.data(), static_cast<long>(target.size()),
                      velocity ? velocity->data() : nullptr, vn)) {
    return std::nullopt;
  }
  const auto start = std::chrono::steady_clock::now();
  const long k = run.next;
  auto q = self.joints();
  const Advance a = run.run->advance(k, k + 1, self.input.position(), self.input.rotation(),
                                     self.input.ff(), self.input.at_rest(), q);
  return self.ran(k, a, start);
}

// Any tasks: one sample's references as Python packed them (as advance takes them).
nb::tuple step_arrays(PyTicker& self, std::optional<In<double>> P_d, std::optional<In<double>> R_d,
                      In<double> FF, In<bool> at_rest, std::optional<In<double>> goal_ref,
                      std::optional<In<double>> goal_ff) {
  PyTrackingRun& run = *self.run;
  self.check_model();
  const TrackingRun& r = *run.run;
  const auto size = [](const std::optional<In<double>>& a) {
    return a ? static_cast<long>(a->size()) : 0L;
  };
  const bool ok = size(P_d) == (r.task().has_position ? 3 : 0) &&
                  size(R_d) == (r.task().has_orientation ? 9 : 0) &&
                  static_cast<long>(FF.size()) == r.primary_rows() && at_rest.size() == 1 &&
                  size(goal_ref) == r.goals().ref_size() && size(goal_ff) == r.goals().rows();
  if (!ok) {
    throw std::invalid_argument(
        "Ticker.step_arrays: one sample's P_d (3), R_d (3, 3), FF (m0), at_rest (1), goal_ref "
        "(D) and goal_ff (M), as the task has them");
  }
  self.input.forget();
  const auto start = std::chrono::steady_clock::now();
  const long k = run.next;
  auto q = self.joints();
  const Advance a = run.run->advance(k, k + 1, P_d ? P_d->data() : nullptr,
                                     R_d ? R_d->data() : nullptr, FF.data(), at_rest.data(), q,
                                     goal_ref ? goal_ref->data() : nullptr,
                                     goal_ff ? goal_ff->data() : nullptr);
  return self.ran(k, a, start);
}

}  // namespace

void bind_ticker(nb::module_& m) {
  m.attr("ROTATION_TOLERANCE") = ROTATION_TOLERANCE;
  nb::class_<PyTicker>(m, "Ticker", "A controller's ticks on an open TrackingRun.")
      .def("__init__", &make_ticker, nb::arg("run"), nb::arg("q").noconvert(),
           nb::arg("qdot").noconvert(),
           nb::arg("tol_position"), nb::arg("tol_orientation"), nb::arg("settling_time"),
           "run: an open TrackingRun; q: the controller's joints (nq,), updated in place; qdot "
           "(nv,): each tick's joint velocity, written.")
      .def("step", &step, nb::arg("target").noconvert(),
           nb::arg("velocity").noconvert().none() = nb::none(),
           "One tick of a one-task run: target a 4x4 pose, a position (3,) or a rotation "
           "(3, 3) (float64, C-contiguous), velocity (6,) or (3,) or None. Returns "
           "(verdict, error, orientation_error, n_events, t_k), or None when the target or the "
           "velocity does not fit the task (nothing run). verdict: 0 ok, 1 deadlock, 2 "
           "violated, 3 diverged, 4 off_track.")
      .def("step_arrays", &step_arrays, nb::arg("P_d").noconvert().none(),
           nb::arg("R_d").noconvert().none(), nb::arg("FF").noconvert(),
           nb::arg("at_rest").noconvert(), nb::arg("goal_ref").noconvert().none() = nb::none(),
           nb::arg("goal_ff").noconvert().none() = nb::none(),
           "One tick with the references Python packed; returns as step.")
      .def_prop_ro("stop",
                   [](const PyTicker& s) {
                     const Advance& a = s.last;
                     return nb::make_tuple(a.next, stop_name(a.stop), a.k, a.r, a.err);
                   },
                   "The last tick's stop, as advance returns it: (next, stop, k, r, err).")
      .def_prop_ro("wall", [](const PyTicker& s) { return s.wall; },
                   "Time spent in the ticks so far [s].")
      .def_prop_ro("above_since", [](const PyTicker& s) { return s.above_since; },
                   "Since when [s] the error is above the tolerance (NaN: it is not).");
}

}  // namespace clik
