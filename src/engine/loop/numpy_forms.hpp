// NumPy arrays and Python values at the ticker's boundary (loop/bind_ticker.cpp,
// loop/measured_input.cpp): what is read in place, and how values are shown back.
#pragma once

#include <string>

#include <nanobind/nanobind.h>

#include "tasks/targets.hpp"

namespace clik {

// A NumPy float64 array read in place: aligned, in the machine's byte order, C-contiguous.
bool plain_doubles(PyObject* o);

// A new NumPy float64 array (n,) holding a copy of v.
nanobind::object array_of(const double* v, long n);

// ``shape (16,)`` as Python writes a shape.
std::string shape_words(const Floats& f);

// The values of a 0-, 1- or 2-D form as Python gives them (a number, a list of lists).
nanobind::object values_of(const Floats& f);

// The value of key `name` in a dict (None: left out).
nanobind::object dict_item(const nanobind::object& map, nanobind::handle name);

// The names, as "a, b, c".
std::string joined(const nanobind::tuple& names);

}  // namespace clik
