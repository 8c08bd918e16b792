// What the tracking loop asks of a run's constraints: see loop/constraint_hooks.hpp;
// the Python specification is clik/loop/tracking.py (_Run.observe_limits, _Run.record).
#include "loop/constraint_hooks.hpp"

#include "constraints/constraint_run.hpp"

namespace clik {

int update_constraints(ConstraintRun& crun, long k, const Vec& q, const pinocchio::Model&,
                       pinocchio::Data& data, ExtendedTask& ext, Law& law, bool exact) {
  return crun.update(k, q, data, ext, law, exact);
}

void observe_constraint_limits(const ConstraintRun& crun, double tk, ViolationMonitor& monitor) {
  crun.observe_limits(tk, monitor);
}

void record_constraints(ConstraintRun& crun, Recorder& rec, long j, int active) {
  rec.constraints(j, active, crun.min_distance());
  crun.record(static_cast<int>(j), rec.ring());
}

}  // namespace clik
