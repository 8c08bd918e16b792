// The Recorder's arrays (clik/loop/recording.py) as the tracking run's binding takes them
// (`_engine.RecordArrays`): written in place, so each must already have its dtype and be
// contiguous (never converted: a converted copy would be written).
#pragma once

#include <cstdint>
#include <optional>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "loop/recording.hpp"

namespace clik {

template <typename T>
using WrittenArray = nanobind::ndarray<T, nanobind::numpy, nanobind::c_contig,
                                       nanobind::device::cpu>;

struct RecordArrays {
  long N = 0, every = 1;
  WrittenArray<std::intptr_t> idx;
  WrittenArray<double> q, qdot, qddot, position;
  std::optional<WrittenArray<double>> reference;
  WrittenArray<double> error;
  std::optional<WrittenArray<double>> orientation_error;
  std::optional<WrittenArray<std::int16_t>> active;
  std::optional<WrittenArray<double>> distance;
  WrittenArray<double> joint_min, joint_max, qdot_prev;
  std::optional<WrittenArray<double>> goal_error;  // (n, G, 2): each goal's error norms
  bool ring = false;  // an open run's: slot j % capacity (N is then LONG_MAX)

  long capacity() const { return static_cast<long>(idx.shape(0)); }
  long nq() const { return static_cast<long>(q.shape(1)); }
  long nv() const { return static_cast<long>(qdot.shape(1)); }

  // Throws std::invalid_argument unless every shape fits N (a ring: any capacity >= 1),
  // every, nq and nv.
  void validate() const;
  RecordBuffers buffers() const;
};

void bind_record(nanobind::module_& m);

}  // namespace clik
