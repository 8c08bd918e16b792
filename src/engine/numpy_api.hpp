// NumPy's C API (its own headers, numpy/arrayobject.h), for the controller's ticks: a
// tick's arrays are made with PyArray_SimpleNew and a target's fields are read with
// NumPy's accessors (PyArray_TYPE, PyArray_DATA, ...), the cheapest ordinary way (a tick
// costs about a microsecond). The API table is imported once, in bindings.cpp (which
// defines CLIK_NUMPY_IMPORT before including this header); every other file includes it
// as is. Built against the NumPy the engine runs with (pyproject.toml's build requirements).
#pragma once

#include <Python.h>

#define PY_ARRAY_UNIQUE_SYMBOL clik_numpy_api
#ifndef CLIK_NUMPY_IMPORT
#define NO_IMPORT_ARRAY
#endif
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
