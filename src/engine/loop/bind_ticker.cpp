// The controller's ticks in the engine (`_engine.Ticker`, used by clik/control/ticks.py):
// one sample of an open run per call, `TrackingRun::advance(k, k + 1)`, and the tick's
// verdict (docs/method.md, "Online control"; the Python form: Controller._verdict and
// Controller._off_track in clik/control/controller.py). `step` reads a frame task's target
// directly (the fast path) and returns the tick itself (`_engine.Tick`: its joints in rows
// of blocks of numpy arrays, its verdict, events and active rows as Python objects, built
// here); `step_arrays` takes the references Python packed (any tasks).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include "boundary.hpp"
#include "loop/py_tick.hpp"
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

constexpr const char* VERDICT_NAMES[] = {"ok", "deadlock", "violated", "diverged", "off_track"};

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
  nb::object empty;                 // numpy.empty
  NumpyTypes numpy;                 // numpy.ndarray and its float64 dtype
  nb::object verdicts[5];           // the verdicts' names
  nb::object no_reason, task_name;  // "" and the one task's name
  RowBlocks q_rows, qdot_rows;
  long seen = 0;                       // events already given in a tick
  std::vector<nb::object> key_names;  // the constraints' names, by key (built when asked)
  PyObject* self_py = nullptr;        // this ticker's Python object (borrowed)
  nb::object general_ref, verdict_ref;  // the controller's methods (WeakMethods; serving)

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

  // The constraint named by key, as a Python string made once.
  const nb::object& key_name(int key) {
    const auto at = static_cast<std::size_t>(key);
    if (at >= key_names.size()) key_names.resize(at + 1);
    if (!key_names[at].is_valid()) key_names[at] = nb::str(run->constraints->name(key).c_str());
    return key_names[at];
  }

  // The run's events [e0, e1) as {t, constraint, action} dicts.
  nb::list events(long e0, long e1) {
    nb::list out;
    const auto& all = run->constraints->events();
    for (long e = e0; e < e1; ++e) {
      const Event& ev = all[static_cast<std::size_t>(e)];
      nb::dict d;
      d["t"] = ev.t;
      d["constraint"] = key_name(ev.key);
      d["action"] = action_name(ev.action);
      out.append(d);
    }
    return out;
  }

  // After the sample k: the tick (the fast path). Its events and active keys are noted
  // here, their Python lists made when read.
  nb::object tick(long k, Advance a, std::chrono::steady_clock::time_point start) {
    run->next = a.next;
    last = a;
    const TrackingRun& r = *run->run;
    Eigen::Map<Vec>(qdot.data(), static_cast<Eigen::Index>(qdot.shape(0))) = r.qdot();
    if (self_py == nullptr) self_py = nb::find(this).ptr();  // borrowed: ticks hold it
    const double tk = r.time(k);
    PyTick out;
    out.code = judge(tk);
    out.t = tk;
    out.k = k;
    out.err = r.last_error();
    out.err_rot = r.last_orientation_error();
    out.q = q_rows.next(q.data(), static_cast<long>(q.shape(0)), empty);
    out.qdot = qdot_rows.next(qdot.data(), static_cast<long>(qdot.shape(0)), empty);
    out.verdict = verdicts[out.code];
    out.reason = no_reason;
    out.ticker = nb::borrow(self_py);
    if (const ConstraintRun* c = run->constraints.get()) {
      out.ev0 = seen;
      out.ev1 = seen = static_cast<long>(c->events().size());
      for (const Candidate& cand : c->active()) {
        if (out.n_active < static_cast<int>(out.keys.size())) {
          out.keys[static_cast<std::size_t>(out.n_active)] = cand.key;
        } else {
          out.more_keys.push_back(cand.key);
        }
        ++out.n_active;
      }
    }
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return nb::cast(std::move(out));
  }

  // One of the served controller's methods (weakly held: the controller holds the ticker).
  static nb::object method(const nb::object& weak) {
    nb::object m = weak.is_valid() ? weak() : nb::none();
    if (m.is_none()) throw std::invalid_argument("Ticker: its controller is gone (serving)");
    return m;
  }
};

void make_ticker(PyTicker* self, nb::object owner, WrittenArray<double> q,
                 WrittenArray<double> qdot, double tol_position, double tol_orientation,
                 double settling_time, const std::string& name, nb::object empty,
                 nb::object ndarray, nb::object float64) {
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
  self->empty = std::move(empty);
  self->numpy = NumpyTypes{std::move(ndarray), std::move(float64)};
  for (int v = 0; v < 5; ++v) self->verdicts[v] = nb::str(VERDICT_NAMES[v]);
  self->no_reason = nb::str("");
  self->task_name = nb::str(name.c_str());
  self->seen = run.constraints ? static_cast<long>(run.constraints->events().size()) : 0;
}

// The fast path's sample: a frame task's target (16, 3 or 9 doubles) and velocity (6, 3 or
// 0 doubles); None when they do not fit the task (nothing run).
nb::object step(PyTicker& self, const double* target, long n, const double* velocity, long vn) {
  PyTrackingRun& run = *self.run;
  self.check_model();
  if (run.run->goals().count() != 0) {  // no std::string built on the fast path
    throw std::invalid_argument("Ticker.serve: one task (step_arrays for several)");
  }
  if (!self.input.set(target, n, velocity, vn)) return nb::none();
  const auto start = std::chrono::steady_clock::now();
  const long k = run.next;
  auto q = self.joints();
  const Advance a = run.run->advance(k, k + 1, self.input.position(), self.input.rotation(),
                                     self.input.ff(), self.input.at_rest(), q);
  return self.tick(k, a, start);
}

// Controller.step itself (the instance's, set by Controller.reset): a one-task target as
// a float64 C-contiguous array (4x4, (3,) or (3, 3); its velocity (6,), (3,) or None) goes
// straight to the engine; anything else (a pin.SE3, a list, moved obstacles, a shape the
// task does not take) to the controller's general step, which checks it and names what is
// wrong. A verdict other than ok gets its reason there.
nb::object serve(PyTicker& self, nb::handle targets, nb::handle velocities, nb::handle obstacles) {
  const auto general = [&]() {
    return PyTicker::method(self.general_ref)(targets, velocities, obstacles);
  };
  if (!obstacles.is_none()) return general();
  Doubles target, velocity;
  if (!target.take(targets, self.numpy)) return general();
  const long n = std::max({target.shaped(4, 4), target.shaped(3, 0), target.shaped(3, 3)});
  long vn = 0;
  if (!velocities.is_none()) {
    if (!velocity.take(velocities, self.numpy)) return general();
    vn = std::max(velocity.shaped(6, 0), velocity.shaped(3, 0));
    if (vn < 0) return general();
  }
  if (n < 0) return general();
  nb::object tick = step(self, target.data(), n, vn > 0 ? velocity.data() : nullptr, vn);
  if (tick.is_none()) return general();
  if (nb::cast<PyTick&>(tick).code != 0) PyTicker::method(self.verdict_ref)(tick);
  return tick;
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

void bind_tick(nb::module_& m) {
  const auto ticker = [](const PyTick& s) -> PyTicker& { return nb::cast<PyTicker&>(s.ticker); };
  nb::class_<PyTick>(m, "Tick",
                     "One tick of a clik.Controller (its fast path): the attributes of "
                     "clik.control.tick.Tick.")
      .def_prop_ro("q", [](PyTick& s) { return s.q.get(); },
                   "q_{k+1}, the joints to command next (nq,) [rad or m]: this tick's own "
                   "array.")
      .def_prop_ro("qdot", [](PyTick& s) { return s.qdot.get(); },
                   "qdot_k, the law's joint velocity (nv,) [rad/s or m/s].")
      .def_ro("t", &PyTick::t, "This tick's time t_k [s].")
      .def_ro("k", &PyTick::k, "This tick's index.")
      .def_ro("code", &PyTick::code,
              "The verdict's code: 0 ok, 1 deadlock, 2 violated, 3 diverged, 4 off_track.")
      .def_ro("verdict", &PyTick::verdict, "ok, deadlock, violated, diverged or off_track.")
      .def_rw("reason", &PyTick::reason, "What happened, with numbers (\"\" when ok).")
      .def_prop_ro("events",
                   [ticker](PyTick& s) {
                     if (!s.events.is_valid()) {
                       s.events = s.ev1 > s.ev0 ? nb::object(ticker(s).events(s.ev0, s.ev1))
                                                : nb::object(nb::list());
                     }
                     return s.events;
                   },
                   "This tick's constraint events, {t, constraint, action} dicts.")
      .def_prop_ro("active",
                   [ticker](PyTick& s) {
                     if (!s.active.is_valid()) {
                       nb::list out;
                       for (int i = 0; i < s.n_active; ++i) {
                         const auto at = static_cast<std::size_t>(i);
                         const int key = at < s.keys.size() ? s.keys[at]
                                                            : s.more_keys[at - s.keys.size()];
                         out.append(ticker(s).key_name(key));
                       }
                       s.active = std::move(out);
                     }
                     return s.active;
                   },
                   "The constraints whose rows are active at this tick, in row order.")
      .def_prop_ro("errors",
                   [ticker](const PyTick& s) {
                     nb::dict d;
                     d[ticker(s).task_name] = nb::make_tuple(s.err, s.err_rot);
                     return d;
                   },
                   "The task's error norms by name, {name: (position [m], orientation [rad])} "
                   "(a new dict at each read).")
      .def_prop_ro("ok", [](const PyTick& s) { return s.code == 0; },
                   "Whether the verdict is ok.")
      .def("__repr__", [](const PyTick& s) {
        return "Tick(k=" + std::to_string(s.k) + ", t=" + std::to_string(s.t) +
               ", verdict=" + nb::cast<std::string>(s.verdict) + ")";
      });
}

void bind_ticker(nb::module_& m) {
  m.attr("ROTATION_TOLERANCE") = ROTATION_TOLERANCE;
  bind_tick(m);
  nb::class_<PyTicker>(m, "Ticker", "A controller's ticks on an open TrackingRun.")
      .def("__init__", &make_ticker, nb::arg("run"), nb::arg("q").noconvert(),
           nb::arg("qdot").noconvert(),
           nb::arg("tol_position"), nb::arg("tol_orientation"), nb::arg("settling_time"),
           nb::arg("name"), nb::arg("empty"), nb::arg("ndarray"), nb::arg("float64"),
           "run: an open TrackingRun; q: the controller's joints (nq,), updated in place; qdot "
           "(nv,): each tick's joint velocity, written; name: the one task's name (the key of "
           "Tick.errors); empty, ndarray, float64: numpy.empty, numpy.ndarray and "
           "numpy.dtype('float64') (the ticks' rows are made with the first; a target of the "
           "other two is read from its fields).")
      .def("step_arrays", &step_arrays, nb::arg("P_d").noconvert().none(),
           nb::arg("R_d").noconvert().none(), nb::arg("FF").noconvert(),
           nb::arg("at_rest").noconvert(), nb::arg("goal_ref").noconvert().none() = nb::none(),
           nb::arg("goal_ff").noconvert().none() = nb::none(),
           "One tick with the references Python packed; returns (verdict code, error, "
           "orientation_error, n_events, t_k) (the caller makes the tick).")
      .def_prop_ro("stop",
                   [](const PyTicker& s) {
                     const Advance& a = s.last;
                     return nb::make_tuple(a.next, stop_name(a.stop), a.k, a.r, a.err);
                   },
                   "The last tick's stop, as advance returns it: (next, stop, k, r, err).")
      .def_rw("seen", &PyTicker::seen, "The constraint events given in ticks so far.")
      .def("serve", &serve, nb::arg("targets"), nb::arg("velocities") = nb::none(),
           nb::arg("obstacles") = nb::none(),
           "Controller.step on the compiled engine's fast path (see clik.Controller.step): a "
           "one-task target as a float64 C-contiguous array runs here, anything else in the "
           "controller's _general_step.")
      .def(
          "serving",
          [](PyTicker& s, nb::object general, nb::object verdict) {
            s.general_ref = std::move(general);
            s.verdict_ref = std::move(verdict);
          },
          nb::arg("general"), nb::arg("verdict"),
          "The served controller's methods, as weakref.WeakMethod: general(targets, velocities, "
          "obstacles) takes what serve() does not; verdict(tick) gives a tick's reason.")
      .def_prop_ro("wall", [](const PyTicker& s) { return s.wall; },
                   "Time spent in the ticks so far [s].")
      .def_prop_ro("above_since", [](const PyTicker& s) { return s.above_since; },
                   "Since when [s] the error is above the tolerance (NaN: it is not).");
}

}  // namespace clik
