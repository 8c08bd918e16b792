// One tick's targets: see tick_targets.hpp and clik/control/ticks.py (the specification).
#include "loop/tick_targets.hpp"

#include <type_traits>

#include "loop/tracking.hpp"

namespace clik {

// -- every task of a tick ---------------------------------------------------------------

TickTargets::TickTargets(const TrackingRun& run)
    : pos_(run.task().has_position), rot_(run.task().has_orientation) {
  const TaskConfig& task = run.task();
  readers_.emplace_back(FrameTarget{task.has_position, task.has_orientation, task.rows, true});
  const Goals& goals = run.goals();
  for (int g = 0; g < goals.count(); ++g) {
    readers_.push_back(goals.target(g));
    ref_at_.push_back(goals.ref_at(g));
    ff_at_.push_back(goals.ff_at(g));
  }
  for (const TargetReader& r : readers_) {
    Floats t, v;
    t.values.assign(static_cast<std::size_t>(largest_target(r)), 0.0);
    v.values.assign(static_cast<std::size_t>(largest_velocity(r)), 0.0);
    targets_.push_back(std::move(t));
    velocities_.push_back(std::move(v));
  }
  ff_.assign(task.rows.size(), 0.0);
  goal_ref_.assign(static_cast<std::size_t>(goals.ref_size()), 0.0);
  goal_ff_.assign(static_cast<std::size_t>(goals.ff_size()), 0.0);
  goal_ref_prev_ = goal_ref_;
}

bool TickTargets::read(int& i, Refusal& why) {
  bool all_velocities = true;
  for (i = 0; i < count(); ++i) {
    const auto at = static_cast<std::size_t>(i);
    const Floats &target = targets_[at], &velocity = velocities_[at];
    all_velocities = all_velocities && velocity.given;
    bool ok;
    if (i == 0) {
      ok = std::get<FrameTarget>(readers_[0]).read(target, velocity, p_.data(), R_.data(),
                                                    ff_.data(), why);
    } else {
      double* ref = goal_ref_.data() + ref_at_[at - 1];
      double* ff = goal_ff_.data() + ff_at_[at - 1];
      ok = std::visit(
          [&](const auto& r) {
            if constexpr (std::is_same_v<std::decay_t<decltype(r)>, ValuesTarget>) {
              return r.read(target, velocity, ref, ff, why);
            } else {  // a frame's pose (p, R) or a centre of mass (p)
              return r.read(target, velocity, ref, ref + 3, ff, why);
            }
          },
          readers_[at]);
    }
    if (!ok) return false;
  }
  bool zero = true;
  for (double f : ff_) zero = zero && f == 0.0;
  for (double f : goal_ff_) zero = zero && f == 0.0;
  // A target given without its velocity may move with a zero feed-forward: at rest only
  // while every target stays where it was at the previous tick (Controller's _unmoved).
  const bool unmoved = started_ && (!pos_ || p_ == p_prev_) && (!rot_ || R_ == R_prev_) &&
                       goal_ref_ == goal_ref_prev_;
  at_rest_ = zero && (all_velocities || unmoved);
  p_prev_ = p_;
  R_prev_ = R_;
  goal_ref_prev_ = goal_ref_;
  started_ = true;
  return true;
}

}  // namespace clik
