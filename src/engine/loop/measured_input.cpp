// The measured joints at the ticker's boundary: loop/measured_input.hpp.
#include "loop/measured_input.hpp"

#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include <nanobind/stl/string.h>

#include "loop/numpy_forms.hpp"
#include "numpy_api.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

nb::object shape_of(PyArrayObject* a) {
  nb::list dims;
  for (int d = 0; d < PyArray_NDIM(a); ++d) dims.append(static_cast<long>(PyArray_DIMS(a)[d]));
  return nb::tuple(dims);
}

nb::object list_of(const Vec& v, long start, long n) {
  nb::list out;
  for (long i = start; i < start + n; ++i) out.append(v[i]);
  return out;
}

}  // namespace

void MeasuredInput::raise(nb::handle field, const std::string& expected, nb::handle got) const {
  nb::object error = refuse(field, expected, got);
  PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
  throw nb::python_error();
}

// q_measured (qdot_measured) into the measured buffer: the same checks, in the same
// order, as MeasuredJoints.stage (shape, finite, rotations).
void MeasuredInput::stage_joints(nb::handle value, bool velocity) {
  const nb::object& field = velocity ? qdot_field : q_field;
  const nb::object& expected = velocity ? velocity_words : words;
  Vec& out = velocity ? measured->qdot() : measured->q();
  nb::object converted;
  PyObject* o = value.ptr();
  if (!plain_doubles(o)) {  // Python code may run here: nothing of the ticker is held
    converted = convert(value, field, expected);
    o = converted.ptr();
    if (!plain_doubles(o)) throw std::logic_error("as_floats: a float64 C-contiguous array");
  }
  auto* a = reinterpret_cast<PyArrayObject*>(o);
  if (PyArray_NDIM(a) != 1 || PyArray_DIMS(a)[0] != out.size()) {
    const std::string shape = nb::cast<std::string>(nb::repr(shape_of(a)));
    raise(field, nb::cast<std::string>(expected), nb::str(("shape " + shape).c_str()));
  }
  std::memcpy(out.data(), PyArray_DATA(a), static_cast<std::size_t>(out.size()) * sizeof(double));
  if (!out.allFinite()) {
    raise(field, "finite numbers: " + nb::cast<std::string>(expected), list_of(out, 0, out.size()));
  }
  if (velocity) return;
  long bad = 0;
  if (!measured->unit_rotations(rotation_tolerance, bad)) {
    const Rotation& r = measured->rotations()[static_cast<std::size_t>(bad)];
    raise(field, nb::cast<std::string>(rotation_words[static_cast<std::size_t>(bad)]),
          list_of(out, r.start, r.size));
  }
}

void MeasuredInput::stage(nb::handle q_in, nb::handle qdot_in) {
  has_q = !q_in.is_none();
  has_qdot = !qdot_in.is_none();
  if (!has_q && has_qdot) raise(qdot_field, "given with q_measured", nb::str("no q_measured"));
  if (has_q) stage_joints(q_in, false);
  if (has_qdot) stage_joints(qdot_in, true);
}

void MeasuredInput::keep(long j) {
  const long nq = commanded.size(), nv = measured->qdot().size();
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  VecMap(rec_commanded.data() + j * nq, nq) = commanded;
  VecMap m(rec_measured.data() + j * nq, nq), md(rec_qdot_measured.data() + j * nv, nv);
  if (has_q) {
    m = measured->q();
  } else {
    m.setConstant(nan);
  }
  if (has_qdot) {
    md = measured->qdot();
  } else {
    md.setConstant(nan);
  }
}

}  // namespace clik
