// What the tracking loop asks of a run's constraints (constraints/): their
// rows for this sample, the penetrations they saw, what they record. Kept
// apart so that loop/tracking.cpp does not depend on the constraint room's insides.
#pragma once

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "loop/laws.hpp"
#include "loop/recording.hpp"
#include "constraints/violations.hpp"
#include "tasks/extended_task.hpp"

namespace clik {

class ConstraintRun;

// Rows of the active constraints written after the task rows; their count.
int update_constraints(ConstraintRun& crun, long k, const Vec& q, const pinocchio::Model& model,
                       pinocchio::Data& data, ExtendedTask& ext, Law& law, bool exact);

// Every limit the constraints guard that is crossed at this sample (a link inside an
// obstacle or another link), to the monitor.
void observe_constraint_limits(const ConstraintRun& crun, double tk, ViolationMonitor& monitor);

// The constraint columns of recorded sample j (active rows, minimum distance, ...).
void record_constraints(ConstraintRun& crun, Recorder& rec, long j, int active);

}  // namespace clik
