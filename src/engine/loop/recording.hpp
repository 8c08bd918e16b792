// The record of a run, written in place into the arrays of the Python
// Recorder (clik/loop/recording.py, which allocates them and trims them after the
// run): every record_every-th sample and the last; running joint extremes. An open run's
// record is a ring: the j-th sample kept goes to slot j % capacity, over the oldest.
#pragma once

#include <cstdint>

#include "types.hpp"

namespace clik {

using RowMap = Eigen::Map<Mat>;
using VecMap = Eigen::Map<Vec>;

// Views of the Recorder's arrays; a null pointer where the Recorder has none.
struct RecordBuffers {
  long N = 0;      // samples in the run (LONG_MAX: an open run)
  long every = 1;  // record_every
  long capacity = 0;
  bool ring = false;  // slot j % capacity (an open run)
  int nq = 0, nv = 0;
  std::intptr_t* idx = nullptr;      // (capacity)
  double* q = nullptr;               // (capacity, nq)
  double* qdot = nullptr;            // (capacity, nv)
  double* qddot = nullptr;           // (capacity, nv)
  double* position = nullptr;        // (capacity, 3)
  double* reference = nullptr;       // (capacity, 3) or null
  double* error = nullptr;           // (capacity)
  double* orientation_error = nullptr;  // (capacity) or null
  std::int16_t* active = nullptr;    // (capacity) or null
  double* distance = nullptr;        // (capacity) or null
  double* joint_min = nullptr;       // (nq)
  double* joint_max = nullptr;       // (nq)
  double* qdot_prev = nullptr;       // (nv)
  double* goal_error = nullptr;      // (capacity, G, 2) or null: each goal's error norms
  int goals = 0;                     // G
};

class Recorder {
 public:
  explicit Recorder(const RecordBuffers& b) : b_(b) {}

  bool due(long k) const { return k % b_.every == 0 || k == b_.N - 1; }

  void start(const Vec& q) {
    VecMap(b_.joint_min, b_.nq) = q;
    VecMap(b_.joint_max, b_.nq) = q;
  }

  // Store sample k; returns its slot (the ring's oldest, once full). Whatever records
  // into that slot then (goals, constraints) overwrites all of it.
  long keep(long k, const Vec& q, const Vec& qdot, const Vec3& position, const double* reference,
            double error, double orientation_error) {
    const long j = b_.ring ? j_ % b_.capacity : j_;
    b_.idx[j] = k;
    VecMap(b_.q + j * b_.nq, b_.nq) = q;
    VecMap(b_.qdot + j * b_.nv, b_.nv) = qdot;
    Eigen::Map<Vec3>(b_.position + 3 * j) = position;
    b_.error[j] = error;
    if (b_.reference != nullptr && reference != nullptr) {
      Eigen::Map<Vec3>(b_.reference + 3 * j) = Eigen::Map<const Vec3>(reference);
    }
    if (b_.orientation_error != nullptr) b_.orientation_error[j] = orientation_error;
    if (b_.every > 1) {
      VecMap(b_.qddot + j * b_.nv, b_.nv) = qdot - VecMap(b_.qdot_prev, b_.nv);
    }
    ++j_;
    return j;
  }

  // Each goal's (first, second) error norms (G, 2) into slot j.
  void goals(long j, const Mat& norms) {
    if (b_.goal_error == nullptr) return;
    double* out = b_.goal_error + 2 * b_.goals * j;
    for (int g = 0; g < b_.goals; ++g) {
      out[2 * g] = norms(g, 0);
      out[2 * g + 1] = norms(g, 1);
    }
  }

  void constraints(long j, int active, double min_distance) {
    if (b_.active != nullptr) b_.active[j] = static_cast<std::int16_t>(active);
    if (b_.distance != nullptr) b_.distance[j] = min_distance;
  }

  // Running extremes and the previous qdot (decimated runs and rings only).
  void every_sample(const Vec& q, const Vec& qdot) {
    if (b_.every > 1 || b_.ring) {
      VecMap lo(b_.joint_min, b_.nq), hi(b_.joint_max, b_.nq);
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
      VecMap(b_.qdot_prev, b_.nv) = qdot;
    }
  }

  long kept() const { return j_; }  // every sample kept so far (a ring holds the last capacity)
  bool ring() const { return b_.ring; }
  long capacity() const { return b_.capacity; }

 private:
  RecordBuffers b_;
  long j_ = 0;
};

}  // namespace clik
