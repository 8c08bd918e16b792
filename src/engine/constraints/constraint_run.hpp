// One run's constraints: the core that every kind shares (mirrors
// clik/constraints/constraint_run.py, its specification): candidates, activation (the
// most violated first, within the bound on active rows (22)), release (the sign rule, or
// the projection rule), events, the active rows' record, names by key. It never names a
// kind: it holds one run of each kind of the set (kinds.hpp), in the set's order, and
// visits them (kind.hpp says what each must do).
//
// Interface for the tracking loop
// -------------------------------
// Set-up, once per run (nothing of it is shared between runs):
//
//   ConstraintSetConfig cfg = ...;   // `_engine.ConstraintSetConfig(...)` from Python
//   ConstraintRun crun(cfg, model, m, law, alpha, t, n_rec, frame, task_rows);
//   int rows = m + std::max(crun.limit(), 0);   // for ExtendedTask and Law
//
//   cfg is copied (the run keeps it; its owners keep the Python model and GeometryModel
//   alive); `model` (the robot's pinocchio::Model, the config's) must outlive the run; t is
//   the run's times (an offline grid is read in place: it must outlive the run); n_rec the
//   recorded samples (Recorder.capacity: a ring's slots); alpha the task's largest gain
//   [1/s]; frame and task_rows the task's frame and rows among (x, y, z, rx, ry, rz) (the
//   dexterity row needs them).
//
// Per sample k, after the loop computed pinocchio::computeJointJacobians(model, data, q)
// and wrote the task rows 0..m of `ext` (J, e, ff; K set at construction):
//
//   int v = crun.update(k, q, data, ext, law, exact);  // exact = this sample is recorded
//   int r = m + v;                                     // the law runs on rows 0..r
//   crun.observe_limits(t[k], monitor);                // limits crossed, to the monitor
//   crun.record(j, ring);                              // when recorded in slot j
//
//   update writes rows m..m+v of ext (J, e, K, ff) and, under the projection rule, may run
//   `law` on ext (law.velocity(ext, r', qdot) with r' < m + v). It allocates nothing in
//   steady state (events aside: a string is made only when accessors are called).
//   min_distance() is then the exact nearest obstacle distance of the sample [m] (inf:
//   none exact).
//
// After the run (bind_constraints.cpp's `constraint_records` hands them to Python):
//   events()        {t (rounded to 9 decimals as Python's round), key, action}: every one,
//                   or the last ones of a bounded log (event_log.hpp)
//   code_keys()     the key of each code used in rec_active (in code order)
//   rec_active(), rec_witness()   per recorded slot
//   skipped_names(), active_names(), limit(), and each kind's records (kind_records).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "constraints/collision_scene.hpp"
#include "constraints/constraint_set.hpp"
#include "constraints/event_log.hpp"
#include "constraints/kind.hpp"
#include "constraints/kinds.hpp"
#include "loop/laws.hpp"
#include "constraints/violations.hpp"
#include "tasks/extended_task.hpp"
#include "types.hpp"

namespace clik {

class ConstraintRun {
 public:
  // Throws std::invalid_argument when the model is not the config's robot, or a kind
  // cannot run (e.g. a dexterity row without the task's frame and rows).
  // m: every task row (the primary's and the extra goals'), the constraint rows' offset;
  // task_m: the primary task's rows (0 .. task_m), those of `frame` and `task_rows`
  // (-1: m, a run with one task); events: the events kept (the last ones; 0: every one).
  ConstraintRun(const ConstraintSetConfig& config, const pinocchio::Model& model, int m,
                LawKind law, double alpha, const Clock& t, int n_rec, int frame = -1,
                std::vector<int> task_rows = {}, int task_m = -1, long events = 0);
  // The kinds point into the run's own copy of the config and scene: neither copied nor moved.
  ConstraintRun(const ConstraintRun&) = delete;
  ConstraintRun& operator=(const ConstraintRun&) = delete;

  // Evaluate, activate, fill the active rows into ext (rows m .. m + v) and release;
  // returns v. data: kinematics and joint Jacobians at q (computeJointJacobians).
  // exact: make every obstacle's nearest distance exact (a recorded sample).
  int update(long k, const Eigen::Ref<const Vec>& q, pinocchio::Data& data, ExtendedTask& ext,
             Law& law, bool exact);

  // Every limit the kinds guard that is crossed at this sample, to the monitor.
  void observe_limits(double tk, ViolationMonitor& monitor) const;

  // An obstacle moved by a controller: at `position` at time tk [s], then `velocity`
  // (every kind is asked; the one that has it moves it). False: no obstacle so named.
  // A cloud replaced by a controller, in the kind that has it; false: none so named.
  bool replace_cloud(const CloudConfig& cloud);
  bool move_obstacle(const std::string& name, const Vec3& position, const Vec3& velocity,
                     const Mat3& rotation, double tk);

  // Keep this sample's active set, witness points and the kinds' records in slot j.
  // ring: slot j was written before (a ring record): its unset entries are reset first.
  void record(int j, bool ring = false);

  // This sample's exact nearest obstacle distance [m] (inf: none exact).
  double min_distance() const { return min_distance_; }

  // -- names and results -----------------------------------------------------------
  int limit() const { return limit_; }
  int n_keys() const { return static_cast<int>(names_.size()); }
  const std::string& name(int key) const { return names_[key]; }
  const std::vector<Candidate>& active() const { return active_; }
  std::vector<std::string> active_names() const;
  // Constraints violated that found no free row, sorted, unique (skipped_names).
  std::vector<std::string> skipped_names() const;
  const EventLog& events() const { return events_; }
  // The events of the last update() (a controller's tick: all of them, whatever the log keeps).
  const std::vector<Event>& sample_events() const { return sample_events_; }
  const std::vector<int>& code_keys() const { return code_keys_; }
  int slots() const { return slots_; }
  const Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& rec_active()
      const {
    return rec_active_;  // (n_rec, slots) codes, -1 where unset
  }
  const Mat& rec_witness() const { return rec_witness_; }  // (n_rec, slots * 6): [a xyz, b xyz]
  int n_kinds() const { return static_cast<int>(kinds_.size()); }
  // Kind `slot`'s records after the run (views into its state).
  std::vector<RecordArray> kind_records(int slot) const;

 private:
  void mark_active();
  void refresh_active(double tk);
  void activate(double tk);
  double gain(int slot, double row_norm2) const;
  int fill_rows(Sample& s, ExtendedTask& ext);
  int project_release(double tk, ExtendedTask& ext, Law& law, int v);
  void event(double tk, int key, EventAction action);

  const ConstraintSetConfig cfg_;
  const pinocchio::Model& model_;
  int m_, task_m_;
  LawKind law_;
  double alpha_;
  int limit_;
  Clock t_;
  std::optional<CollisionScene> scene_;  // shared by the kinds that measure distances
  std::vector<KindRun> kinds_;           // in the set's order
  std::vector<std::string> names_;       // by key; each kind's keys follow the previous'
  double min_distance_ = INF;

  // candidates and the active set (buffers at their largest sizes)
  std::vector<Candidate> cand_, active_, still_;
  std::vector<int> fresh_, cur_index_, marked_;
  std::vector<char> is_active_, skipped_, in_fresh_, ever_skipped_;
  std::vector<int> skipped_list_;
  Vec qdot_;
  Vec q_prev_, dq_;  // |dq| since the previous sample, for the kinds' certificates
  bool has_prev_ = false;

  // records
  EventLog events_;
  std::vector<Event> sample_events_;  // the last update()'s (room for every key's three)
  std::vector<int> code_of_key_, code_keys_;
  int slots_;
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rec_active_;
  Mat rec_witness_;
};

}  // namespace clik
