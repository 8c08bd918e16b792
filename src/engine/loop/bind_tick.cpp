// The tick a controller's step returns on the compiled engine (`_engine.Tick`, made by
// loop/bind_ticker.cpp; see loop/py_tick.hpp): its attributes, read from its own copies.
#include <string>

#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

#include "loop/py_tick.hpp"
#include "numpy_api.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

// A tick's joints (joint velocities): an array viewing the tick's own copy (its base the
// tick). A new array at each read (an array kept by the tick would be a reference cycle).
nb::object view_of(nb::handle tick, const Small<double, 16>& values) {
  npy_intp n = static_cast<npy_intp>(values.size());
  PyObject* a = PyArray_New(&PyArray_Type, 1, &n, NPY_DOUBLE, nullptr,
                            const_cast<double*>(values.data()), 0, NPY_ARRAY_CARRAY, nullptr);
  if (a == nullptr) throw nb::python_error();
  nb::object array = nb::steal(a);
  Py_INCREF(tick.ptr());  // stolen by the array
  if (PyArray_SetBaseObject(reinterpret_cast<PyArrayObject*>(a), tick.ptr()) < 0) {
    throw nb::python_error();
  }
  return array;
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
      .def_prop_ro("q", [](nb::handle s) { return view_of(s, nb::inst_ptr<PyTick>(s)->q); },
                   "q_{k+1}, the joints to command next (nq,) [rad or m]: the tick's own.")
      .def_prop_ro("qdot",
                   [](nb::handle s) { return view_of(s, nb::inst_ptr<PyTick>(s)->qdot); },
                   "qdot_k, the law's joint velocity (nv,) [rad/s or m/s]: the tick's own.")
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
