// A controller's ticks in the engine (`_engine.Ticker`, held by clik.Controller; the
// specification is clik/control/ticks.py's PythonTicks): one sample of an open run per
// step, `TrackingRun::advance(k, k + 1)`, from each task's target of this tick, with the
// tick's verdict (docs/method.md, "Online control").
//
// A step runs in phases, so that nothing of the engine is held across a Python call:
//   1. the controller's turn (loop/turn.hpp): one thread at a time;
//   2. stage: every task's target and velocity, and q_measured and qdot_measured, copied
//      out of the caller's objects into the ticker's own buffers (a NumPy float64 array
//      read in place through NumPy's C API; any other form converted by
//      clik.control.targets.as_floats first: Python runs here), their shapes, finiteness
//      and rotations checked (loop/measured.hpp);
//   3. read and run: the tasks' readers check the numbers once (tasks/targets.hpp), the
//      measured joints' jump (M3) is judged, the run advances one sample from them (M1),
//      and the tick's values are copied out (C++ only);
//   4. the tick made as a Python object (its arrays, copies), its reason asked of Python
//      when its verdict is not ok.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "boundary.hpp"
#include "loop/measured_input.hpp"
#include "loop/numpy_forms.hpp"
#include "loop/py_tick.hpp"
#include "loop/py_tracking_run.hpp"
#include "loop/tick_targets.hpp"
#include "loop/turn.hpp"
#include "model/model_bridge.hpp"
#include "numpy_api.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

enum Verdict : int {
  ok = 0, deadlock = 1, violated = 2, diverged = 3, off_track = 4, measurement_jump = 5
};
constexpr int VERDICT_COUNT = 6;
constexpr const char* VERDICT_NAMES[] = {"ok",       "deadlock",  "violated",
                                         "diverged", "off_track", "measurement_jump"};

// The tolerance of the off_track verdict: position [m], orientation [rad], settling [s].
struct TickTolerance {
  double position, orientation, settling;
};

struct PyTicker {
  nb::object turn_ref;  // the controller's Turn (shared with its other methods)
  Turn* turn;
  nb::object refuse;       // clik.InputError
  nb::object convert;      // clik.control.targets.as_floats(value, field, expected)
  nb::object as_mapping;   // clik.control.targets.as_mapping(value, field, names)
  nb::object check_model;  // the robot's check_model (raises clik.InputError)
  nb::tuple task_names;
  nb::handle tick_type;  // _engine.Tick (the module keeps it)
  std::vector<nb::object> fields, velocity_fields;  // "targets['name']", "velocities['name']"
  TickTolerance tol;
  nb::object verdicts[VERDICT_COUNT], no_reason;
  MeasuredInput mi;  // q_measured, qdot_measured (loop/measured_input.hpp)

  // the session (restart)
  nb::object owner;  // the PyTrackingRun (kept alive)
  PyTrackingRun* run = nullptr;
  const pinocchio::Model* model = nullptr;  // the run's (its Python object kept by the run)
  nb::object explain;                       // (tick, stop, above_since) -> reason
  std::unique_ptr<TickTargets> targets;
  std::vector<std::string> target_words, velocity_words;
  Vec q;
  nb::tuple constraint_names;
  long notes = 0;
  double wall = 0.0;  // time in the ticks [s]
  double above_since = std::numeric_limits<double>::quiet_NaN();
  Advance last;

  void must_hold(const char* who) const {
    if (!turn->mine()) throw std::logic_error(std::string(who) + ": the controller's turn");
  }

  [[noreturn]] void raise(nb::handle field, const std::string& expected, nb::handle got) const {
    nb::object error = refuse(field, expected, got);
    PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
    throw nb::python_error();
  }

  // -- phase 2: the caller's objects into the ticker's buffers --------------------------

  // One target (velocity) of task i: its shape, and its values when the task takes it.
  void stage(int i, nb::handle value, bool velocity) {
    const auto at = static_cast<std::size_t>(i);
    nb::object converted;
    PyObject* o = value.ptr();
    if (!plain_doubles(o)) {  // Python code may run here: nothing of the ticker is held
      const nb::object field = velocity ? velocity_fields[at] : fields[at];
      const nb::str words((velocity ? velocity_words[at] : target_words[at]).c_str());
      converted = convert(value, field, words);
      o = converted.ptr();
      if (!plain_doubles(o)) throw std::logic_error("as_floats: a float64 C-contiguous array");
    }
    auto* a = reinterpret_cast<PyArrayObject*>(o);
    Floats& f = velocity ? targets->velocity(i) : targets->target(i);
    const npy_intp* dims = PyArray_DIMS(a);
    f.given = true;
    f.ndim = std::min(PyArray_NDIM(a), Floats::MAX_DIMS);
    std::copy(dims, dims + f.ndim, f.shape);
    const TargetReader& reader = targets->reader(i);
    const long n = velocity ? velocity_size(reader, f) : target_size(reader, f);
    if (n < 0) {
      const std::string got = shape_words(f);
      raise(velocity ? velocity_fields[at] : fields[at],
            velocity ? velocity_words[at] : target_words[at], nb::str(got.c_str()));
    }
    std::memcpy(f.values.data(), PyArray_DATA(a), static_cast<std::size_t>(n) * sizeof(double));
  }

  // targets (velocities) by task name: a dict (read as is), anything as_mapping makes a
  // dict of; else None: the value of the one task itself. Every key must name a task and,
  // for the targets, every task have one.
  nb::object by_name(nb::handle value, const char* field, bool every) const {
    const int n = targets->count();
    nb::object map;
    if (PyDict_Check(value.ptr())) {
      map = nb::borrow(value);
    } else if (n == 1 && plain_doubles(value.ptr())) {
      return nb::none();
    } else {
      map = as_mapping(value, field, task_names);
      if (map.is_none()) {
        if (n == 1) return map;
        raise(nb::str(field),
              std::string("a mapping of task name to ") + (every ? "target" : "velocity") +
                  " (" + joined(task_names) + ")",
              value);
      }
    }
    Py_ssize_t found = 0;
    for (nb::handle name : task_names) {
      const int has = PyDict_Contains(map.ptr(), name.ptr());
      if (has < 0) throw nb::python_error();
      found += has;
    }
    if (PyDict_Size(map.ptr()) > found) unknown_key(map, field);
    if (every && found < n) {
      raise(nb::str(field), "a target for every task (" + joined(task_names) + ")", nb::none());
    }
    return map;
  }

  // The first key of a mapping that names no task: refused.
  [[noreturn]] void unknown_key(const nb::object& map, const char* field) const {
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(map.ptr(), &pos, &key, &value)) {
      const nb::object k = nb::borrow(key);  // held: comparing may run Python code
      int found = 0;
      for (nb::handle name : task_names) {
        const int eq = PyObject_RichCompareBool(k.ptr(), name.ptr(), Py_EQ);
        if (eq < 0) throw nb::python_error();
        found += eq;
      }
      if (found == 0) {
        const std::string names = nb::cast<std::string>(nb::repr(nb::list(task_names)));
        raise(nb::str(field), "task names among " + names, k);
      }
    }
    throw std::logic_error("Ticker: a mapping with a key that names no task");
  }

  void stage_all(nb::handle targets_in, nb::handle velocities_in) {
    const nb::object tmap = by_name(targets_in, "targets", true);
    const bool moving = !velocities_in.is_none();
    const nb::object vmap = moving ? by_name(velocities_in, "velocities", false) : nb::none();
    for (int i = 0; i < targets->count(); ++i) {
      const nb::handle name = task_names[static_cast<std::size_t>(i)];
      stage(i, tmap.is_none() ? nb::borrow(targets_in) : dict_item(tmap, name), false);
      const nb::object velocity =
          !moving ? nb::none() : vmap.is_none() ? nb::borrow(velocities_in) : dict_item(vmap, name);
      if (velocity.is_none()) {
        targets->velocity(i).given = false;
      } else {
        stage(i, velocity, true);
      }
    }
  }

  // -- phase 3: read and run -------------------------------------------------------------

  // The verdict of the sample just run at time tk (the worst that holds).
  int judge(double tk) {
    const TrackingRun& r = *run->run;
    const long before = notes;
    notes = r.monitor().notes();
    if (last.stop == Stop::deadlock || last.stop == Stop::stall) return deadlock;
    if (last.stop != Stop::none) return diverged;
    if (mi.jumped) return measurement_jump;
    if (notes != before) return violated;
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

  // A refusal by task i's reader, raised as clik.InputError.
  [[noreturn]] void refused(int i, const Refusal& why) const {
    const auto at = static_cast<std::size_t>(i);
    Floats f = why.velocity ? targets->velocity(i) : targets->target(i);  // a copy
    if (why.show == Refusal::Show::last_row) {  // a 4x4's last row
      std::vector<double> row(f.values.begin() + 12, f.values.begin() + 16);
      f.values = std::move(row);
      f.ndim = 1;
      f.shape[0] = 4;
    }
    raise(why.velocity ? velocity_fields[at] : fields[at], why.expected, values_of(f));
  }

  nb::object step(nb::handle targets_in, nb::handle velocities_in, nb::handle q_in,
                  nb::handle qdot_in, bool held) {
    std::optional<Turn::Held> turn_held;
    if (held) {
      must_hold("Ticker.step(held=True)");
    } else {
      turn_held.emplace(*turn, "Controller.step");
    }
    stage_all(targets_in, velocities_in);
    mi.stage(q_in, qdot_in);
    if (!(ModelShape::of(*model) == run->built)) {  // changed meanwhile: named by the robot
      check_model();
      raise(nb::str("robot.model"), "the model the controller was built on", nb::none());
    }
    int i = 0;
    Refusal why;
    if (!targets->read(i, why)) refused(i, why);
    // the tick's Python object first (a Python allocation: nothing of the engine held)
    nb::object tick = nb::inst_alloc(tick_type);
    PyTick& out = *new (nb::inst_ptr<PyTick>(tick)) PyTick();
    nb::inst_mark_ready(tick);
    const auto start = std::chrono::steady_clock::now();
    const long k = run->next;
    TrackingRun& r = *run->run;
    mi.commanded = q;  // q_k, the controller's own
    mi.jumped = false;
    if (mi.has_q) {  // (M1): the law runs at q_m unless (M3) refuses it
      ++mi.given;
      mi.jumped = mi.measured->jumped(*model, k, mi.jump);
      if (!mi.jumped) q = mi.measured->q();
    }
    const long kept = r.kept();
    last = r.advance(k, k + 1, targets->P_d(), targets->R_d(), targets->FF(),
                     targets->at_rest(), q, targets->goal_ref(), targets->goal_ff());
    run->next = last.next;
    if (mi.has_q && !mi.jumped) {  // (M2): q_{k+1} = q_k (+) qdot_k dt, or q_k held (diverged)
      const bool held =
          last.stop != Stop::none && last.stop != Stop::deadlock && last.stop != Stop::stall;
      if (held) {
        q = mi.commanded;
      } else {
        mi.measured->integrate(*model, mi.commanded, r.qdot(), q);
      }
    }
    if (r.kept() != kept) mi.keep(kept % mi.rec_commanded.shape(0));
    const double tk = r.time(k);
    out.code = judge(tk);
    out.t = tk;
    out.k = k;
    out.verdict = verdicts[out.code];
    out.reason = no_reason;
    out.task_names = task_names;
    out.constraint_names = constraint_names;
    const Mat& goals = r.goal_last();
    out.errors.reserve(static_cast<std::size_t>(2 + 2 * goals.rows()));
    out.errors.push_back(r.last_error());
    out.errors.push_back(r.last_orientation_error());
    for (Eigen::Index g = 0; g < goals.rows(); ++g) {
      out.errors.push_back(goals(g, 0));
      out.errors.push_back(goals(g, 1));
    }
    if (const ConstraintRun* c = run->constraints.get()) {
      out.events = c->sample_events();
      out.active.reserve(c->active().size());
      for (const Candidate& cand : c->active()) out.active.push_back(cand.key);
    }
    out.q.assign(q.data(), static_cast<std::size_t>(q.size()));
    const Vec& qdot = r.qdot();
    out.qdot.assign(qdot.data(), static_cast<std::size_t>(qdot.size()));
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (out.code != ok) {  // its reason, in Python (nothing of the engine held)
      nb::object jumped_tuple = nb::none();
      const Jump& j = mi.jump;
      if (mi.jumped) jumped_tuple = nb::make_tuple(j.i, j.size, j.limit, j.k_accepted, j.n);
      nb::object reason = explain(tick, stop_tuple(), above_since, jumped_tuple);
      nb::inst_ptr<PyTick>(tick)->reason = std::move(reason);
    }
    return tick;
  }

  nb::tuple stop_tuple() const {
    return nb::make_tuple(last.next, stop_name(last.stop), last.k, last.r, last.err);
  }

  // A new session on an open run from q0 (the controller's turn held by reset).
  void restart(nb::object run_owner, const Eigen::Ref<const Vec>& q0, nb::object explainer,
               WrittenArray<double> q_commanded, WrittenArray<double> q_measured,
               WrittenArray<double> qdot_measured) {
    must_hold("Ticker.restart");
    PyTrackingRun& r = nb::cast<PyTrackingRun&>(run_owner);
    require(r.run->is_open(), "Ticker.restart: an open TrackingRun (t None)");
    require(q0.size() == r.record.nq(), "Ticker.restart: q0 (nq,)");
    const long cap = r.record.capacity();
    const auto fits = [cap](const WrittenArray<double>& a, long n) {
      return a.ndim() == 2 && static_cast<long>(a.shape(0)) == cap &&
             static_cast<long>(a.shape(1)) == n;
    };
    require(fits(q_commanded, r.record.nq()) && fits(q_measured, r.record.nq()) &&
                fits(qdot_measured, r.record.nv()),
            "Ticker.restart: the measured record (capacity, nq), (capacity, nq), "
            "(capacity, nv)");
    require(r.record.nv() == mi.bound_size, "Ticker.restart: the jump bound (nv,)");
    const pinocchio::Model& m = borrow_model(r.model.ptr());
    require_same_model(r.built, m, "Ticker.restart");
    auto in = std::make_unique<TickTargets>(*r.run);
    require(in->count() == static_cast<int>(task_names.size()),
            "Ticker.restart: the run has one task per name");
    std::vector<std::string> tw, vw;
    for (int i = 0; i < in->count(); ++i) {
      tw.push_back(target_forms(in->reader(i)));
      vw.push_back(velocity_forms(in->reader(i)));
    }
    std::vector<std::string> keys;  // copied first: nothing of the run held across Python calls
    for (int key = 0; r.constraints && key < r.constraints->n_keys(); ++key) {
      keys.push_back(r.constraints->name(key));
    }
    nb::list names;
    for (const std::string& key : keys) names.append(nb::str(key.c_str()));
    owner = std::move(run_owner);
    run = &r;
    model = &m;
    explain = std::move(explainer);
    targets = std::move(in);
    target_words = std::move(tw);
    velocity_words = std::move(vw);
    q = q0;
    mi.measured->restart(q0);
    mi.commanded = q0;
    mi.rec_commanded = std::move(q_commanded);
    mi.rec_measured = std::move(q_measured);
    mi.rec_qdot_measured = std::move(qdot_measured);
    mi.given = 0;
    mi.has_q = mi.has_qdot = mi.jumped = false;
    constraint_names = nb::tuple(names);
    notes = 0;
    wall = 0.0;
    above_since = std::numeric_limits<double>::quiet_NaN();
    last = Advance{};
  }
};

void make_ticker(PyTicker* self, nb::object turn, nb::object refuse, nb::object convert,
                 nb::object as_mapping, nb::object check_model, std::vector<std::string> names,
                 double tol_position, double tol_orientation, double settling_time, double dt,
                 const Eigen::Ref<const Vec>& jump_bound, nb::list rotations,
                 double rotation_tolerance, std::string measured_words,
                 std::string measured_velocity_words) {
  require(!names.empty(), "Ticker: names, one per task");
  require(finite_positive(tol_position) && finite_positive(tol_orientation) &&
              finite_positive(settling_time),
          "Ticker: tolerance (position [m], orientation [rad]) and settling_time [s], > 0");
  Turn& t = nb::cast<Turn&>(turn);
  new (self) PyTicker{};
  self->turn_ref = std::move(turn);
  self->turn = &t;
  self->refuse = std::move(refuse);
  self->convert = std::move(convert);
  self->mi.refuse = self->refuse;
  self->mi.convert = self->convert;
  self->as_mapping = std::move(as_mapping);
  self->check_model = std::move(check_model);
  nb::list task_names;
  for (const std::string& name : names) {
    nb::str s(name.c_str());
    task_names.append(s);
    nb::object quoted = nb::repr(s);
    self->fields.push_back(nb::str(("targets[" + nb::cast<std::string>(quoted) + "]").c_str()));
    self->velocity_fields.push_back(
        nb::str(("velocities[" + nb::cast<std::string>(quoted) + "]").c_str()));
  }
  self->task_names = nb::tuple(task_names);
  self->tick_type = nb::type<PyTick>();
  self->tol = {tol_position, tol_orientation, settling_time};
  for (int v = 0; v < VERDICT_COUNT; ++v) self->verdicts[v] = nb::str(VERDICT_NAMES[v]);
  require(finite_positive(rotation_tolerance), "Ticker: rotation_tolerance > 0");
  for (Eigen::Index i = 0; i < jump_bound.size(); ++i) {
    require(jump_bound[i] > 0.0, "Ticker: jump_bound (nv,), > 0 (inf: none)");
  }
  std::vector<Rotation> rs;
  for (nb::handle item : rotations) {  // (start, size, expected) as rotation_slices gives
    const nb::tuple t = nb::cast<nb::tuple>(item);
    require(t.size() == 3, "Ticker: rotations, (start, size, expected) each");
    const Rotation rot{nb::cast<long>(t[0]), nb::cast<long>(t[1])};
    require(rot.start >= 0 && (rot.size == 2 || rot.size == 4), "Ticker: a rotation's start, size");
    rs.push_back(rot);
    self->mi.rotation_words.push_back(nb::borrow(t[2]));
  }
  require(finite_positive(dt), "Ticker: dt > 0 [s]");
  self->mi.measured = std::make_unique<Measured>(Vec(jump_bound), std::move(rs), dt);
  self->mi.bound_size = static_cast<long>(jump_bound.size());
  self->mi.rotation_tolerance = rotation_tolerance;
  self->mi.q_field = nb::str("q_measured");
  self->mi.qdot_field = nb::str("qdot_measured");
  self->mi.words = nb::str(measured_words.c_str());
  self->mi.velocity_words = nb::str(measured_velocity_words.c_str());
  self->no_reason = nb::str("");
}

}  // namespace

void bind_ticker(nb::module_& m) {
  m.attr("ROTATION_TOLERANCE") = ROTATION_TOLERANCE;
  bind_turn(m);
  bind_tick(m);
  nb::class_<PyTicker>(m, "Ticker", "A controller's ticks on an open TrackingRun.")
      .def("__init__", &make_ticker, nb::kw_only(), nb::arg("turn"), nb::arg("refuse"),
           nb::arg("convert"), nb::arg("as_mapping"), nb::arg("check_model"), nb::arg("names"),
           nb::arg("tol_position"), nb::arg("tol_orientation"), nb::arg("settling_time"),
           nb::arg("dt"), nb::arg("jump_bound").noconvert(), nb::arg("rotations"),
           nb::arg("rotation_tolerance"), nb::arg("measured_words"),
           nb::arg("measured_velocity_words"),
           "turn: the controller's Turn; refuse: clik.InputError; convert(value, field, "
           "expected): a target or velocity as a float64 C-contiguous array (or raises); "
           "as_mapping(value, field, names): a dict, or None for a value that is no mapping; "
           "check_model(): raises when the robot's model changed; names: the tasks'; "
           "dt: the tick [s]; jump_bound: (M3)'s b (nv,) [rad or m], inf: none; rotations: (start, size, "
           "expected) of each unit rotation in q; measured_words (measured_velocity_words): "
           "what q_measured (qdot_measured) must be. Then restart() gives it a session.")
      .def("restart", &PyTicker::restart, nb::arg("run"), nb::arg("q0").noconvert(),
           nb::arg("explain"), nb::arg("q_commanded").noconvert(),
           nb::arg("q_measured").noconvert(), nb::arg("qdot_measured").noconvert(),
           "A new session (the turn held): run an open TrackingRun, q0 (nq,), explain(tick, "
           "stop, above_since, jump) -> the reason of a verdict other than ok; the measured "
           "record's arrays (capacity, nq), (capacity, nq), (capacity, nv), written.")
      .def(
          "step",
          [](PyTicker& s, nb::handle targets, nb::handle velocities, nb::handle q_measured,
             nb::handle qdot_measured) {
            require(s.run != nullptr, "Ticker.step: restart() first");
            return s.step(targets, velocities, q_measured, qdot_measured, false);
          },
          nb::arg("targets").none(), nb::arg("velocities").none(),
          nb::arg("q_measured").none() = nb::none(), nb::arg("qdot_measured").none() = nb::none(),
          "One tick (Controller.step): the targets, velocities, q_measured and qdot_measured "
          "(None: none) as the controller takes them.")
      .def(
          "step_held",
          [](PyTicker& s, nb::handle targets, nb::handle velocities, nb::handle q_measured,
             nb::handle qdot_measured) {
            require(s.run != nullptr, "Ticker.step_held: restart() first");
            return s.step(targets, velocities, q_measured, qdot_measured, true);
          },
          nb::arg("targets").none(), nb::arg("velocities").none(),
          nb::arg("q_measured").none() = nb::none(), nb::arg("qdot_measured").none() = nb::none(),
          "step_held(targets, velocities): step() when the caller holds the turn already "
          "(obstacles moved first).")
      .def_prop_ro("k", [](const PyTicker& s) { return s.run ? s.run->next : 0L; },
                   "The next tick's index.")
      .def_prop_ro("q", [](const PyTicker& s) { return array_of(s.q.data(), s.q.size()); },
                   "The joints the next tick starts from (a copy).")
      .def_prop_ro("measured_given", [](const PyTicker& s) { return s.mi.given; },
                   "Ticks of this session given q_measured.")
      .def_prop_ro("wall", [](const PyTicker& s) { return s.wall; },
                   "Time spent in the ticks of this session [s].");
}

}  // namespace clik
