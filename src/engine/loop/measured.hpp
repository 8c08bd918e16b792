// A controller's measured joints (docs/method.md, "Measured joints", (M1)-(M3); the
// specification is clik/control/measured.py, MeasuredJoints): a measurement's rotations
// made unit, the jump (M3) against the last accepted joints, the commanded joints'
// integration (M2).
// Everything is allocated at the session's start: a tick allocates nothing.
#pragma once

#include <vector>

#include <pinocchio/multibody/fwd.hpp>

#include "types.hpp"

namespace clik {

// A unit rotation in q: a (cos, sin) pair (size 2) or a quaternion (size 4) at start.
struct Rotation {
  long start = 0, size = 0;
};

// (M3) found: velocity coordinate i moved `size` since the accepted joints of tick
// k_accepted, above its bound `limit` = b_i n, n ticks later.
struct Jump {
  long i = 0;
  double size = 0.0, limit = 0.0;
  long k_accepted = 0, n = 1;
};

class Measured {
 public:
  // bound: b_i = c vmax_i dt (nv) [rad or m], inf where no bound; rotations in q.
  Measured(Vec bound, std::vector<Rotation> rotations, double dt)
      : bound_(std::move(bound)), rotations_(std::move(rotations)), dt_(dt) {}

  // A new session from q0 (nq): q0 is the accepted joints of tick 0.
  void restart(const Eigen::Ref<const Vec>& q0);

  // The staged measurement's buffers (nq, nv), written by the ticker's boundary.
  Vec& q() { return q_; }
  Vec& qdot() { return qdot_; }

  // q()'s rotations divided by their norm; false (nothing changed) at the first whose
  // norm is off 1 by more than tolerance: its index.
  bool unit_rotations(double tolerance, long& bad);
  const std::vector<Rotation>& rotations() const { return rotations_; }

  // (M3) at tick k: true and `out` when q() jumped, else q() accepted from tick k on.
  bool jumped(const pinocchio::Model& model, long k, Jump& out);

  // (M2): out = q (+) qdot dt (q the commanded joints, qdot the law's at the measured).
  void integrate(const pinocchio::Model& model, const Vec& q, const Vec& qdot, Vec& out);

 private:
  Vec bound_;
  std::vector<Rotation> rotations_;
  double dt_;                    // the tick [s]
  Vec q_, qdot_, accepted_, d_;  // the staged q_m, qdot_m; q_a; q_m (-) q_a (nv)
  Vec dq_;                       // qdot dt (nv)
  long k_accepted_ = 0;
};

}  // namespace clik
