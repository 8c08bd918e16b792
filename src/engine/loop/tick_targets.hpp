// One tick's targets (a controller's; the specification is clik/control/ticks.py): every
// task's target and velocity, as the Ticker copied them, read by the task's own reader
// (tasks/targets.hpp) into the one-sample references TrackingRun::advance takes (P_d, R_d
// and FF for the primary task; goal_ref and goal_ff for the others), with the tick's
// at_rest (the stall check's).
#pragma once

#include <array>
#include <vector>

#include "tasks/targets.hpp"

namespace clik {

class TrackingRun;  // loop/tracking.hpp

// Every task's target of one tick: the primary task's first, then the goals', in row order.
class TickTargets {
 public:
  // The readers of the run's tasks (the primary's TaskConfig, each goal's target()).
  explicit TickTargets(const TrackingRun& run);

  int count() const { return static_cast<int>(readers_.size()); }
  const TargetReader& reader(int i) const { return readers_[static_cast<std::size_t>(i)]; }
  Floats& target(int i) { return targets_[static_cast<std::size_t>(i)]; }
  Floats& velocity(int i) { return velocities_[static_cast<std::size_t>(i)]; }

  // Every task's staged target and velocity into this tick's references and at_rest;
  // false at the first refusal (task `i`, why). Nothing is kept of a refused tick.
  bool read(int& i, Refusal& why);
  // A new session: the next tick counts as moved (at_rest needs its velocities).
  void restart() { started_ = false; }

  const double* P_d() const { return pos_ ? p_.data() : nullptr; }
  const double* R_d() const { return rot_ ? R_.data() : nullptr; }
  const double* FF() const { return ff_.data(); }
  const bool* at_rest() const { return &at_rest_; }
  const double* goal_ref() const { return goal_ref_.empty() ? nullptr : goal_ref_.data(); }
  const double* goal_ff() const { return goal_ff_.empty() ? nullptr : goal_ff_.data(); }

 private:
  std::vector<TargetReader> readers_;
  std::vector<Floats> targets_, velocities_;
  std::vector<int> ref_at_, ff_at_;  // each goal's first reference double and row
  bool pos_, rot_;
  // this tick's references, then the previous tick's (a target unmoved since)
  std::array<double, 3> p_{}, p_prev_{};
  std::array<double, 9> R_{}, R_prev_{};
  std::vector<double> ff_, goal_ref_, goal_ff_, goal_ref_prev_;
  bool at_rest_ = false, started_ = false;
};

}  // namespace clik
