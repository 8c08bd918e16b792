// NumPy arrays and Python values at the ticker's boundary: loop/numpy_forms.hpp.
#include "loop/numpy_forms.hpp"

#include <cstring>

#include <nanobind/stl/string.h>

#include "numpy_api.hpp"

namespace nb = nanobind;

namespace clik {

bool plain_doubles(PyObject* o) {
  if (!PyArray_Check(o)) return false;
  auto* a = reinterpret_cast<PyArrayObject*>(o);
  return PyArray_TYPE(a) == NPY_DOUBLE && PyArray_ISCARRAY_RO(a) && PyArray_ISNOTSWAPPED(a);
}

nb::object array_of(const double* v, long n) {
  npy_intp size = n;
  PyObject* a = PyArray_SimpleNew(1, &size, NPY_DOUBLE);
  if (a == nullptr) throw nb::python_error();
  std::memcpy(PyArray_DATA(reinterpret_cast<PyArrayObject*>(a)), v,
              static_cast<std::size_t>(n) * sizeof(double));
  return nb::steal(a);
}

std::string shape_words(const Floats& f) {
  std::string s = "shape (";
  for (int i = 0; i < f.ndim; ++i) s += (i ? ", " : "") + std::to_string(f.shape[i]);
  return s + (f.ndim == 1 ? ",)" : ")");
}

nb::object values_of(const Floats& f) {
  if (f.ndim == 0) return nb::float_(f.values[0]);
  nb::list out;
  if (f.ndim == 1) {
    for (long i = 0; i < f.shape[0]; ++i) out.append(f.values[static_cast<std::size_t>(i)]);
    return out;
  }
  for (long i = 0; i < f.shape[0]; ++i) {
    nb::list row;
    for (long j = 0; j < f.shape[1]; ++j) {
      row.append(f.values[static_cast<std::size_t>(i * f.shape[1] + j)]);
    }
    out.append(row);
  }
  return out;
}

nb::object dict_item(const nb::object& map, nb::handle name) {
  PyObject* v = PyDict_GetItemWithError(map.ptr(), name.ptr());
  if (v == nullptr && PyErr_Occurred()) throw nb::python_error();
  return v == nullptr ? nb::none() : nb::borrow(v);
}

std::string joined(const nb::tuple& names) {
  std::string s;
  for (nb::handle name : names) s += (s.empty() ? "" : ", ") + nb::cast<std::string>(nb::str(name));
  return s;
}

}  // namespace clik
