// The kinds of task a run's goals may be, in one place (mirrors clik/tasks/registry.py).
//
// A kind is a config type and a run type (see goal_kind.hpp); adding one is its header in
// tasks/ (a source beside it if it wants one: distance_goal.hpp and gaze_goal.hpp need
// none) and its place in the list below. Nothing else names a kind: the goals'
// core (Goals), the ticker and the bindings visit these variants.
#pragma once

#include <variant>

#include "tasks/com_goal.hpp"
#include "tasks/distance_goal.hpp"
#include "tasks/frame_goal.hpp"
#include "tasks/gaze_goal.hpp"
#include "tasks/posture_goal.hpp"

namespace clik {

using GoalConfig = std::variant<FrameGoal, PostureGoal, ComGoal, DistanceGoal, GazeGoal>;

namespace detail {
template <typename Configs>
struct GoalKinds;
template <typename... Config>
struct GoalKinds<std::variant<Config...>> {
  using Run = std::variant<typename Config::Run...>;
  template <typename F>
  static void each(F&& f) {
    (f(static_cast<Config*>(nullptr)), ...);
  }
};
}  // namespace detail

// Each kind's run, alternative for alternative.
using GoalRun = detail::GoalKinds<GoalConfig>::Run;

// f(static_cast<Config*>(nullptr)) for each kind's config type, in order (bindings).
template <typename F>
void for_each_goal_config(F&& f) {
  detail::GoalKinds<GoalConfig>::each(f);
}

}  // namespace clik
