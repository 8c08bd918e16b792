// One tick of a controller as the compiled engine returns it (`_engine.Tick`, made in
// loop/bind_ticker.cpp; its Python form is clik.control.tick.Tick). Everything a tick
// holds is its own: its joints, events, active rows and errors are copied when the tick is
// made; `tick.q` and `tick.qdot` are arrays of their own, copied from the tick's when first
// read (the engine never writes them), and the names it reads them by are immutable tuples. So a tick may be read from any thread, at any time, whatever the
// controller does meanwhile.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

#include <nanobind/nanobind.h>

#include "constraints/event_log.hpp"

namespace clik {

// Up to N values in place, more on the heap, contiguous (a tick's joints, active rows and
// errors: most ticks allocate nothing).
template <typename T, std::size_t N>
class Small {
 public:
  void push_back(T v) {
    if (!heap_ && n_ < N) {
      in_place_[n_++] = v;
      return;
    }
    to_heap(n_ + 1);
    more_.push_back(v);
    ++n_;
  }
  // Room for n values: pushing up to n allocates once at most.
  void reserve(std::size_t n) {
    if (n > N) to_heap(n);
  }
  // The n values at p, replacing any: one allocation at most.
  void assign(const T* p, std::size_t n) {
    n_ = n;
    if (!heap_ && n <= N) {
      std::copy(p, p + n, in_place_.begin());
    } else {
      more_.assign(p, p + n);
      heap_ = true;
    }
  }
  std::size_t size() const { return n_; }
  T operator[](std::size_t i) const { return data()[i]; }
  const T* data() const { return heap_ ? more_.data() : in_place_.data(); }

 private:
  void to_heap(std::size_t n) {
    if (heap_) {
      more_.reserve(n);
      return;
    }
    more_.reserve(std::max(n, 2 * N));
    more_.assign(in_place_.begin(), in_place_.begin() + static_cast<std::ptrdiff_t>(n_));
    heap_ = true;
  }
  std::array<T, N> in_place_;  // the first n_ set (until heap_)
  std::vector<T> more_;        // every value, once heap_
  std::size_t n_ = 0;
  bool heap_ = false;
};

// Joints of up to JOINTS_IN_PLACE values are kept in the tick itself (an arm's); a tick
// stays under CPython's small-object size (512 bytes), allocated by its pool, not malloc.
constexpr std::size_t JOINTS_IN_PLACE = 8;
using Joints = Small<double, JOINTS_IN_PLACE>;

// Made in place in its Python object (loop/bind_ticker.cpp).
struct PyTick {
  Joints q, qdot;  // q_{k+1} (nq), qdot_k (nv)
  double t = 0.0;
  long k = 0;
  int code = 0;  // the verdict's: 0 ok, 1 deadlock, 2 violated, 3 diverged, 4 off_track,
                 // 5 measurement_jump
  nanobind::object verdict, reason;
  nanobind::object task_names, constraint_names;  // tuples: by task, by constraint key
  std::vector<Event> events;                       // this tick's
  Small<int, 6> active;                            // the active rows' keys, in row order
  Small<double, 4> errors;                         // (first, second) per task
  nanobind::object q_array, qdot_array;            // copies of q, qdot made when first read
  nanobind::object events_list, active_list;       // made when first read
};

void bind_tick(nanobind::module_& m);  // loop/bind_tick.cpp

}  // namespace clik
