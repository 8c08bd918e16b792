// What a controller's tick returns on the compiled engine's fast path (`_engine.Tick`,
// loop/bind_ticker.cpp) and how the fast path reads a target: numpy rows handed out one
// per tick, and float64 arrays read in place.
#pragma once

#include <array>
#include <cstring>
#include <vector>

#include <Python.h>
#include <nanobind/nanobind.h>

#include "loop/bind_record.hpp"

namespace clik {

// A row of a block of rows (RowBlocks): its numpy view made when first asked.
struct LazyRow {
  nanobind::object block;
  long row = 0;
  nanobind::object view;

  nanobind::object get() {
    if (!view.is_valid()) {
      PyObject* v = PySequence_GetItem(block.ptr(), row);
      if (v == nullptr) throw nanobind::python_error();
      view = nanobind::steal(v);
    }
    return view;
  }
};

// Rows handed out one per tick: a (ROWS, n) float64 array, a new one when used up (a
// tick's row keeps its block alive; a block no tick holds is freed). A row is written
// once: each tick's q is its own array, nothing copied when it is read.
class RowBlocks {
 public:
  static constexpr long ROWS = 256;  // rows per block

  LazyRow next(const double* values, long n, const nanobind::object& empty) {
    if (row_ == ROWS) {
      block_ = empty(nanobind::make_tuple(ROWS, n));
      data_ = nanobind::cast<WrittenArray<double>>(block_).data();
      row_ = 0;
    }
    std::memcpy(data_ + row_ * n, values, static_cast<std::size_t>(n) * sizeof(double));
    return LazyRow{block_, row_++, nanobind::object()};
  }

 private:
  nanobind::object block_;
  double* data_ = nullptr;
  long row_ = ROWS;
};

// One tick as the fast path returns it (`_engine.Tick`: clik.control.tick.Tick's
// attributes). Its lists and arrays are made when first read (then kept).
struct PyTick {
  LazyRow q, qdot;
  double t = 0.0;
  long k = 0;
  int code = 0;
  nanobind::object verdict, reason;
  nanobind::object ticker;             // the PyTicker: the names and the run's events
  long ev0 = 0, ev1 = 0;         // this tick's events: the run's [ev0, ev1)
  int n_active = 0;              // the active rows' keys: keys, then more_keys
  std::array<int, 8> keys{};
  std::vector<int> more_keys;
  nanobind::object events, active;     // made when first read
  double err = 0.0, err_rot = 0.0;
};

// numpy's array object: its first fields, numpy's public ABI (the PyArray_DATA,
// PyArray_NDIM, PyArray_DIMS, PyArray_DESCR and PyArray_FLAGS accessors read them).
struct NumpyHead {
  PyObject_HEAD
  char* data;
  int nd;
  Py_ssize_t* dimensions;
  Py_ssize_t* strides;
  PyObject* base;
  PyObject* descr;
  int flags;
};
constexpr int NUMPY_C_CONTIGUOUS = 0x0001;  // NPY_ARRAY_C_CONTIGUOUS

// What a float64 array is, for Doubles: numpy's ndarray type and its float64 dtype.
struct NumpyTypes {
  nanobind::object ndarray, float64;
};

// A float64 C-contiguous array read in place (no conversion, nothing allocated): a numpy
// ndarray of dtype float64 from its fields; any other object through the buffer protocol.
class Doubles {
 public:
  // False unless `obj` holds C-contiguous float64 data of 1 or 2 dimensions.
  bool take(nanobind::handle obj, const NumpyTypes& np) {
    if (Py_TYPE(obj.ptr()) == reinterpret_cast<PyTypeObject*>(np.ndarray.ptr())) {
      const auto* a = reinterpret_cast<const NumpyHead*>(obj.ptr());
      if (a->descr != np.float64.ptr() || !(a->flags & NUMPY_C_CONTIGUOUS)) return false;
      data_ = reinterpret_cast<const double*>(a->data);
      ndim_ = a->nd;
      shape_ = a->dimensions;
      return ndim_ == 1 || ndim_ == 2;
    }
    if (PyObject_GetBuffer(obj.ptr(), &view_, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) != 0) {
      PyErr_Clear();
      return false;
    }
    held_ = true;
    const char* f = view_.format;
    const bool d = f != nullptr && (f[0] == 'd' || ((f[0] == '<' || f[0] == '=' || f[0] == '@') &&
                                                     f[1] == 'd')) &&
                   (f[0] == 'd' ? f[1] == 0 : f[2] == 0);
    data_ = static_cast<const double*>(view_.buf);
    ndim_ = view_.ndim;
    shape_ = view_.shape;
    return d && view_.itemsize == 8 && (ndim_ == 1 || ndim_ == 2);
  }
  ~Doubles() {
    if (held_) PyBuffer_Release(&view_);
  }
  Doubles() = default;
  Doubles(const Doubles&) = delete;
  Doubles& operator=(const Doubles&) = delete;

  const double* data() const { return data_; }
  // Its size when its shape is (rows,) (cols 0) or (rows, cols), else -1.
  long shaped(long rows, long cols) const {
    const bool ok = cols == 0 ? ndim_ == 1 && shape_[0] == rows
                              : ndim_ == 2 && shape_[0] == rows && shape_[1] == cols;
    return ok ? rows * (cols == 0 ? 1 : cols) : -1;
  }

 private:
  Py_buffer view_{};
  bool held_ = false;
  const double* data_ = nullptr;
  int ndim_ = 0;
  const Py_ssize_t* shape_ = nullptr;
};

}  // namespace clik
