// The tick a controller's step returns on the compiled engine (`_engine.Tick`, made by
// loop/bind_ticker.cpp; see loop/py_tick.hpp): its attributes, read from its own copies.
#include <algorithm>
#include <string>

#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

#include "loop/py_tick.hpp"
#include "numpy_api.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

// A tick's joints (joint velocities): an array of its own, a copy of the tick's made when
// first read and kept (the tick's other attributes are too). It does not refer back to the
// tick: keeping `tick.q` keeps 8 bytes a joint, not the tick.
nb::object array_of(const Joints& values, nb::object& kept) {
  if (!kept.is_valid()) {
    npy_intp n = static_cast<npy_intp>(values.size());
    PyObject* a = PyArray_SimpleNew(1, &n, NPY_DOUBLE);
    if (a == nullptr) throw nb::python_error();
    std::copy(values.data(), values.data() + values.size(),
              static_cast<double*>(PyArray_DATA(reinterpret_cast<PyArrayObject*>(a))));
    kept = nb::steal(a);
  }
  return kept;
}

// The active rows' names, or this tick's events, as Python lists (made when first read).
nb::object active_of(PyTick& s) {
  if (!s.active_list.is_valid()) {
    nb::list out;
    const auto names = nb::borrow<nb::tuple>(s.constraint_names);
    for (std::size_t i = 0; i < s.active.size(); ++i) {
      out.append(names[static_cast<std::size_t>(s.active[i])]);
    }
    s.active_list = std::move(out);
  }
  return s.active_list;
}

nb::object events_of(PyTick& s) {
  if (!s.events_list.is_valid()) {
    nb::list out;
    const auto names = nb::borrow<nb::tuple>(s.constraint_names);
    for (const Event& e : s.events) {
      nb::dict d;
      d["t"] = e.t;
      d["constraint"] = names[static_cast<std::size_t>(e.key)];
      d["action"] = action_name(e.action);
      out.append(d);
    }
    s.events_list = std::move(out);
  }
  return s.events_list;
}

nb::dict errors_of(const PyTick& s) {
  nb::dict d;
  const auto names = nb::borrow<nb::tuple>(s.task_names);
  for (std::size_t i = 0; i < names.size(); ++i) {
    d[names[i]] = nb::make_tuple(s.errors[2 * i], s.errors[2 * i + 1]);
  }
  return d;
}

}  // namespace

void bind_tick(nb::module_& m) {
  nb::class_<PyTick>(m, "Tick",
                     "One tick of a clik.Controller on the compiled engine: the attributes of "
                     "clik.control.tick.Tick (read-only; its own data, safe from any thread).")
      .def_prop_ro("q", [](PyTick& s) { return array_of(s.q, s.q_array); },
                   "q_{k+1}, the joints to command next (nq,) [rad or m]: the tick's own array "
                   "(the same one at each read).")
      .def_prop_ro("qdot", [](PyTick& s) { return array_of(s.qdot, s.qdot_array); },
                   "qdot_k, the law's joint velocity (nv,) [rad/s or m/s]: the tick's own "
                   "array (the same one at each read).")
      .def_ro("t", &PyTick::t, "This tick's time t_k [s].")
      .def_ro("k", &PyTick::k, "This tick's index.")
      .def_ro("code", &PyTick::code,
              "The verdict's code: 0 ok, 1 deadlock, 2 violated, 3 diverged, 4 off_track.")
      .def_ro("verdict", &PyTick::verdict, "ok, deadlock, violated, diverged or off_track.")
      .def_ro("reason", &PyTick::reason, "What happened, with numbers (\"\" when ok).")
      .def_prop_ro("events", &events_of,
                   "This tick's constraint events, {t, constraint, action} dicts.")
      .def_prop_ro("active", &active_of,
                   "The constraints whose rows are active at this tick, in row order.")
      .def_prop_ro("errors", &errors_of,
                   "Each task's error norms by name, {name: (first, second)} (a new dict at "
                   "each read).")
      .def_prop_ro("ok", [](const PyTick& s) { return s.code == 0; }, "Whether the verdict is ok.")
      .def("__repr__", [](const PyTick& s) {
        return "Tick(k=" + std::to_string(s.k) + ", t=" + std::to_string(s.t) +
               ", verdict=" + nb::cast<std::string>(s.verdict) + ")";
      });
}

}  // namespace clik
