// Step 4b of a sample: the law's joint velocity within the joint speed limits,
// docs/method.md "Joint speed limits in the law", (S1)-(S3) (mirrors
// clik/loop/speed_step.py, the specification). Allocated once per run.
#pragma once

#include "tasks/extended_task.hpp"
#include "types.hpp"

namespace clik {

// The bounds of one run (`_engine.LawConfig`'s vmax, amax): velocity v_i [rad/s or
// m/s] finite > 0 per coordinate, or empty (no speed step); acceleration a_i
// [rad/s^2 or m/s^2] > 0 (inf: none) per coordinate, or empty (none at all).
// (S2) leaves out a part's components below this fraction of its largest: rounding (a
// null-space part's 1e-16 on a joint held at its bound would stop the whole level); the
// final clip keeps the box (clik/loop/speed_step.py's NEGLIGIBLE).
constexpr double NEGLIGIBLE = 1e-9;

struct SpeedBounds {
  Vec velocity;
  Vec acceleration;
};

class SpeedStep {
 public:
  SpeedStep(const SpeedBounds& bounds, double dt, int nv);

  bool enabled() const { return v_.size() > 0; }

  // Brings qdot within the bounds in place. qdot_c: the constraint level's part of
  // law (10), or null (laws (9), (8): J_c^T K_c e_c from ext's rows m..r).
  void apply(const ExtendedTask& ext, int r, const Vec* qdot_c, Eigen::Ref<Vec> qdot);

  // The same with law (10)'s parts by levels (1 + L, nv) (Law::parts()): (S1) on the
  // constraint part, then (S2) on each level's part in turn with the room left,
  // u += fit(u, t_l) t_l for l = 1 .. L.
  void apply_levels(const Mat& parts, Eigen::Ref<Vec> qdot);

 private:
  bool within(const Eigen::Ref<const Vec>& qdot) const;
  double box_scale(const Vec& c) const;              // (S1)
  double fit(const Vec& u, const Vec& t) const;      // (S2)
  double accel_scale(const Vec& change) const;       // (S3)

  Vec v_, a_dt_, prev_, c_, u_, t_;
  bool accel_ = false;
};

}  // namespace clik
