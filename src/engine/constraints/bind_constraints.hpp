// Python side of the constraints, for the other rooms' bindings (the tracking loop):
// a ConstraintConfig from a Python ConstraintSet, and what ConstraintRun.finish puts
// in the result, as Python objects.
#pragma once

#include <nanobind/nanobind.h>

#include "constraints/constraint_run.hpp"
#include "constraints/constraint_set.hpp"

namespace clik {

// Everything a run needs from a clik.constraints.ConstraintSet, read from its
// attributes now (robot.model, obstacles, obs_threshold, obs_vel, joint_limits, scene,
// link_labels, gains, form, release_rule, ...). The scene's GeometryModel is borrowed
// (kept alive by the config's owner), the motion bounds rho computed in C++.
ConstraintConfig config_from_set(nanobind::handle cset);

// ConstraintRun.finish's material for the first n_rec recorded slots, as a dict:
//   events               [{"t", "constraint", "action"}]          -> result.events
//   constraint_names     [str] (code order)                       -> info["constraint_names"]
//   active (n_rec, slots) int32, witness (n_rec, slots, 2, 3)     -> extra["active"], ["witness"]
//   obstacle_distance (n_rec, n_obs), obstacle_link int16         (only with obstacles)
//   min_obstacle_distance_by_obstacle, ..._link_by_obstacle, ..._exact_by_obstacle,
//   ..._time_by_obstacle: {obstacle name: value}, min_obstacle_distance (None without
//   obstacles)                                                    -> info["summary_extra"]
//   skipped              [str] sorted                             -> skipped_names()
// The set-level parts of finish (info["obstacles"], info["links"], joint_limits_used)
// come from the Python ConstraintSet itself.
nanobind::dict constraint_records(const ConstraintRun& run, int n_rec);

}  // namespace clik
