// What the tracking loop asks of a run's constraints: see constraint_hooks.hpp;
// the Python specification is clik/tracking.py (_Run.observe_limits, _Run.record).
#include "constraint_hooks.hpp"

#include "constraints/constraint_run.hpp"

namespace clik {

int update_constraints(ConstraintRun& crun, long k, const Vec& q, const pinocchio::Model&,
                       pinocchio::Data& data, ExtendedTask& ext, Law& law, bool exact) {
  return crun.update(static_cast<int>(k), q, data, ext, law, exact);
}

void observe_penetrations(ConstraintRun& crun, double tk, ViolationMonitor& monitor) {
  if (crun.min_distance < 0.0) {  // a penetrating pair is always evaluated: exact
    const ConstraintConfig& cfg = crun.config();
    for (int o = 0; o < crun.dist_o.size(); ++o) {
      if (crun.dist_o[o] < 0.0) {
        monitor.observe_penetration(tk, cfg.pair_name(crun.link_o[o], o), crun.dist_o[o]);
      }
    }
  }
  for (const auto& [key, distance] : crun.self_penetrations) {
    monitor.observe_penetration(tk, crun.name(key), distance);
  }
}

void record_constraints(ConstraintRun& crun, Recorder& rec, long j, int active) {
  rec.constraints(j, active, crun.min_distance);
  crun.record(static_cast<int>(j));
}

}  // namespace clik
