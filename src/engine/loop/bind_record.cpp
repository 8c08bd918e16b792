// `_engine.RecordArrays`: see loop/bind_record.hpp.
#include "loop/bind_record.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include <nanobind/stl/optional.h>

namespace nb = nanobind;

namespace clik {

namespace {
template <typename T>
using Array = WrittenArray<T>;
}  // namespace

void RecordArrays::validate() const {
  const long n = idx.ndim() == 1 ? capacity() : -1, every_ = std::max(every, 1L);
  const long kept = ring ? 1 : N < 1 ? 0 : (N - 1) / every_ + 1 + ((N - 1) % every_ ? 1 : 0);
  auto shaped = [](const auto& a, long rows, long cols) {
    return (cols < 0 ? a.ndim() == 1 : a.ndim() == 2 && static_cast<long>(a.shape(1)) == cols) &&
           static_cast<long>(a.shape(0)) == rows;
  };
  const bool ok =
      (ring || N >= 1) && every >= 1 && n >= kept && q.ndim() == 2 &&
      qdot.ndim() == 2 && shaped(q, n, nq()) && shaped(qdot, n, nv()) &&
      shaped(qddot, n, nv()) && shaped(position, n, 3) && shaped(error, n, -1) &&
      (!reference || shaped(*reference, n, 3)) &&
      (!orientation_error || shaped(*orientation_error, n, -1)) &&
      (!active || shaped(*active, n, -1)) && (!distance || shaped(*distance, n, -1)) &&
      shaped(joint_min, nq(), -1) && shaped(joint_max, nq(), -1) && shaped(qdot_prev, nv(), -1) &&
      (!goal_error || (goal_error->ndim() == 3 && static_cast<long>(goal_error->shape(0)) == n &&
                       goal_error->shape(2) == 2));
  if (!ok) {
    throw std::invalid_argument(
        "RecordArrays: idx (n,), q (n, nq), qdot and qddot (n, nv), position and reference "
        "(n, 3), error, orientation_error, active and distance (n,), joint_min and joint_max "
        "(nq,), qdot_prev (nv,), goal_error (n, G, 2), with n >= the samples kept of N every "
        "`every` (ring: n >= 1, N ignored)");
  }
}

RecordBuffers RecordArrays::buffers() const {
  RecordBuffers b;
  b.N = N;
  b.every = every;
  b.capacity = capacity();
  b.ring = ring;
  b.nq = static_cast<int>(nq());
  b.nv = static_cast<int>(nv());
  b.idx = idx.data();
  b.q = q.data();
  b.qdot = qdot.data();
  b.qddot = qddot.data();
  b.position = position.data();
  b.reference = reference ? reference->data() : nullptr;
  b.error = error.data();
  b.orientation_error = orientation_error ? orientation_error->data() : nullptr;
  b.active = active ? active->data() : nullptr;
  b.distance = distance ? distance->data() : nullptr;
  b.joint_min = joint_min.data();
  b.joint_max = joint_max.data();
  b.qdot_prev = qdot_prev.data();
  b.goal_error = goal_error ? goal_error->data() : nullptr;
  b.goals = goal_error ? static_cast<int>(goal_error->shape(1)) : 0;
  return b;
}

void bind_record(nb::module_& m) {
  nb::class_<RecordArrays>(m, "RecordArrays",
                           "The Recorder's arrays (clik.loop.recording), written in place.")
      .def(
          "__init__",
          [](RecordArrays* self, long N, long every, Array<std::intptr_t> idx, Array<double> q,
             Array<double> qdot, Array<double> qddot, Array<double> position,
             std::optional<Array<double>> reference, Array<double> error,
             std::optional<Array<double>> orientation_error,
             std::optional<Array<std::int16_t>> active, std::optional<Array<double>> distance,
             Array<double> joint_min, Array<double> joint_max, Array<double> qdot_prev,
             std::optional<Array<double>> goal_error, bool ring) {
            RecordArrays r{N,         every,  idx,      q,         qdot,      qddot,
                           position,  reference, error, orientation_error, active, distance,
                           joint_min, joint_max, qdot_prev, goal_error, ring};
            r.validate();
            if (ring) r.N = std::numeric_limits<long>::max();  // an open run: no last sample
            new (self) RecordArrays(std::move(r));
          },
          nb::kw_only(), nb::arg("N"), nb::arg("every"), nb::arg("idx").noconvert(),
          nb::arg("q").noconvert(), nb::arg("qdot").noconvert(), nb::arg("qddot").noconvert(),
          nb::arg("position").noconvert(), nb::arg("reference").noconvert().none(),
          nb::arg("error").noconvert(), nb::arg("orientation_error").noconvert().none(),
          nb::arg("active").noconvert().none(), nb::arg("distance").noconvert().none(),
          nb::arg("joint_min").noconvert(), nb::arg("joint_max").noconvert(),
          nb::arg("qdot_prev").noconvert(), nb::arg("goal_error").noconvert().none() = nb::none(),
          nb::arg("ring") = false,
          "Each array as the Recorder allocated it (its dtype, contiguous: never converted), "
          "reference, orientation_error, active and distance None where it has none. ring: an "
          "open run's record (TrackingRun(t=None)), the j-th sample kept in slot j % capacity; "
          "N is then ignored (LONG_MAX).")
      .def_ro("N", &RecordArrays::N)
      .def_ro("every", &RecordArrays::every)
      .def_ro("ring", &RecordArrays::ring)
      .def_prop_ro("capacity", &RecordArrays::capacity);
}

}  // namespace clik
