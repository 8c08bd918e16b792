// Python side of the constraints, for the other rooms' bindings (the tracking loop):
// what a run's constraints recorded, as Python objects.
#pragma once

#include <nanobind/nanobind.h>

#include "constraints/constraint_run.hpp"

namespace clik {

// The run's constraint records for the first n_rec recorded slots, as a dict:
//   events            [{"t", "constraint", "action"}]
//   constraint_names  [str] (code order): the name of each code in `active`
//   active (n_rec, slots) int32 codes (-1: none), witness (n_rec, slots, 2, 3) [m]
//   active_names      [str] active when the run ended, in row order
//   skipped           [str] sorted: violated constraints that found no free row
//   limit             the bound on active rows
//   kinds             per kind, in the set's order: its records ({} if none), e.g. the
//                     obstacle kind's obstacle_distance (n_rec, n_obs), obstacle_link
//                     (n_rec, n_obs) int16, run_min, run_min_link ([int], -1: none),
//                     run_min_t (n_obs)
nanobind::dict constraint_records(const ConstraintRun& run, int n_rec);

}  // namespace clik
