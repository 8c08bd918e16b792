// Python entry point of a tracking run (used by clik/loop/compiled_run.py): Python
// builds the robot, the reference chunks and the record arrays, and hands them over
// as typed configs; the engine runs the samples and writes the record in place.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/variant.h>
#include <nanobind/stl/vector.h>

#include "bindings.hpp"
#include "boundary.hpp"
#include "constraints/bind_constraints.hpp"
#include "constraints/constraint_run.hpp"
#include "loop/bind_record.hpp"
#include "loop/py_tracking_run.hpp"
#include "loop/recording.hpp"
#include "loop/tracking.hpp"
#include "model/model_bridge.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

template <typename T>
using Array = WrittenArray<T>;

// The run's times: the grid t (N,) of an offline run, read in place; without t an open
// run's t0 + k dt (dt: the law's), whose record is a ring (and a ring's run is open).
Clock run_clock(const std::optional<In<double>>& t, double t0, const LawConfig& law,
                const RecordArrays& record, const pinocchio::Model& m) {
  require(!t == record.ring,
          "TrackingRun: t None (an open run) needs RecordArrays(ring=True), and a "
          "RecordArrays(ring=True) needs t None");
  require(std::isfinite(t0), "TrackingRun: t0, a finite time [s]");
  const bool shaped = !t || (t->ndim() == 1 && static_cast<long>(t->shape(0)) == record.N);
  require(shaped && record.nq() == m.nq && record.nv() == m.nv,
          "TrackingRun: t (N,) and the record's nq, nv are the model's");
  if (!t) return Clock::open(t0, law.settings.dt);
  const Eigen::Map<const Vec> grid(t->data(), static_cast<Eigen::Index>(t->shape(0)));
  require(grid.allFinite(), "TrackingRun: t, finite times [s]");
  return Clock::grid(t->data(), static_cast<long>(t->shape(0)));
}

void make_run(PyTrackingRun* self, nb::object model, const TaskConfig& task,
              const LawConfig& law, const StopConfig& stop, std::optional<In<double>> t,
              double t0, const RecordArrays& record, JointMonitorConfig joints,
              const std::optional<ConstraintSetConfig>& constraints,
              const std::vector<GoalConfig>& goals, long events) {
  require(events >= 0, "TrackingRun: events, the constraint events kept (>= 1; 0: every one)");
  const pinocchio::Model& m = borrow_model(model.ptr());
  // The goals' rows (checked against the model: Goals throws naming the goal and field).
  const Goals goal_rows(m, goals);
  const int m0 = static_cast<int>(task.rows.size());
  const int m_all = m0 + goal_rows.rows();
  require(!record.goal_error || static_cast<int>(record.goal_error->shape(1)) == goal_rows.count(),
          "RecordArrays: goal_error (n, G, 2), G the run's goals (" +
              std::to_string(goal_rows.count()) + ")");
  const Clock times = run_clock(t, t0, law, record, m);
  require_window(stop.deadlock_window, law.settings.dt, "deadlock_window");
  require_window(stop.stall_window, law.settings.dt, "stall_window");
  for (Eigen::Index i = 0; i < law.K_task.size(); ++i) {
    require(finite_positive(law.K_task[i]), "LawConfig: K_task, finite gains > 0 [1/s]");
  }
  std::unique_ptr<ConstraintRun> crun;
  if (constraints) {
    const int m_rows = m_all;
    require(ModelShape::of(*constraints->model) == ModelShape::of(m),
            "TrackingRun: the constraints are on a pin.Model of other sizes than the task's");
    crun = std::make_unique<ConstraintRun>(*constraints, m, m_rows, law.settings.kind, law.alpha,
                                           times, static_cast<int>(record.capacity()), task.frame,
                                           task.rows, m0, events);
    if (m_rows + std::max(crun->limit(), 0) > law.rows) {
      throw std::invalid_argument(
          "LawConfig.rows: fewer than the task's and the constraints' rows");
    }
  }
  // The extended task's room: the task's rows and at most one row per joint more.
  require(law.rows <= m_all + std::max(m.nv, 0), "LawConfig.rows: at most the task's rows + nv");
  auto run = std::make_unique<TrackingRun>(m, task, law, stop, times, record.buffers(),
                                           std::move(joints), crun.get(), goals);
  new (self) PyTrackingRun{std::move(model), ModelShape::of(m), 0,    false, std::move(t),
                           record,           std::move(crun),   std::move(run)};
}

nb::tuple advance(PyTrackingRun& self, long c0, long c1, std::optional<In<double>> P_d,
                  std::optional<In<double>> R_d, In<double> FF, In<bool> at_rest,
                  Array<double> q, std::optional<In<double>> goal_ref,
                  std::optional<In<double>> goal_ff) {
  require_same_model(self.built, borrow_model(self.model.ptr()), "TrackingRun.advance");
  require(!self.stopped, "advance: the run has stopped; build a new TrackingRun");
  if (!(c0 == self.next && c1 >= c0 && c1 <= self.record.N)) {  // the message only then
    const std::string N = self.record.ring ? "an open run: none" : std::to_string(self.record.N);
    require(false, "advance: c0 the next sample (" + std::to_string(self.next) +
                       ") and c0 <= c1 <= N (" + N + ")");
  }
  const auto n = static_cast<std::size_t>(c1 - c0);
  const auto m = static_cast<std::size_t>(self.run->primary_rows());
  const Goals& goals = self.run->goals();
  const TaskConfig& task = self.run->task();
  auto shaped = [n](const auto& a, std::initializer_list<std::size_t> tail) {
    if (a.ndim() != 1 + tail.size() || a.shape(0) != n) return false;
    std::size_t d = 1;
    for (std::size_t s : tail) {
      if (a.shape(d++) != s) return false;
    }
    return true;
  };
  const bool ok = shaped(FF, {m}) && shaped(at_rest, {}) &&
                  (P_d ? shaped(*P_d, {3}) : !task.has_position) &&
                  (R_d ? shaped(*R_d, {3, 3}) : !task.has_orientation) && q.ndim() == 1 &&
                  static_cast<long>(q.shape(0)) == static_cast<long>(self.record.nq());
  if (!ok) {
    throw std::invalid_argument(
        "advance: FF (c1 - c0, m), at_rest (c1 - c0,), P_d (c1 - c0, 3) (None only without "
        "position rows), R_d (c1 - c0, 3, 3) (None only without orientation rows), q (nq,)");
  }
  const auto D = static_cast<std::size_t>(goals.ref_size());
  const auto M = static_cast<std::size_t>(goals.ff_size());
  const bool goals_ok = goals.count() == 0
                            ? !goal_ref && !goal_ff
                            : goal_ref && goal_ff && shaped(*goal_ref, {D}) && shaped(*goal_ff, {M});
  if (!goals_ok) {
    throw std::invalid_argument(
        "advance: goal_ref (c1 - c0, " + std::to_string(D) + ") and goal_ff (c1 - c0, " +
        std::to_string(M) + "), C-contiguous float64, with goals only");
  }
  Advance a;
  {
    nb::gil_scoped_release release;
    Eigen::Map<Vec> qv(q.data(), static_cast<Eigen::Index>(q.shape(0)));
    a = self.run->advance(c0, c1, P_d ? P_d->data() : nullptr, R_d ? R_d->data() : nullptr,
                          FF.data(), at_rest.data(), qv, goal_ref ? goal_ref->data() : nullptr,
                          goal_ff ? goal_ff->data() : nullptr);
  }
  self.next = a.next;
  self.stopped = a.stop != Stop::none && !self.run->is_open();  // an open run goes on
  return nb::make_tuple(a.next, stop_name(a.stop), a.k, a.r, a.err);
}

// The extra goals (tasks/goals.hpp) and the objectives (loop/objectives.hpp).
void bind_goals(nb::module_& m) {
  for_each_goal_config([&](auto* kind) { std::remove_pointer_t<decltype(kind)>::bind(m); });
  nb::class_<ObjectiveConfig>(m, "ObjectiveConfig",
                              "A null-space objective of eq. (5): kind, gain [1/s], level.")
      .def(
          "__init__",
          [](ObjectiveConfig* self, const std::string& kind, double gain, int level,
             std::vector<int> idx_q, std::vector<int> idx_v, const std::optional<Vec>& center,
             const std::optional<Vec>& half_range, const std::optional<Vec>& q_ref) {
            const ObjectiveKind k = objective_kind(kind);
            require(std::isfinite(gain) && gain >= 0.0, "ObjectiveConfig: gain, finite >= 0 [1/s]");
            require(level >= 1, "ObjectiveConfig: level >= 1");
            if (k == ObjectiveKind::joint_centering) {
              require(center && half_range && center->size() == half_range->size() &&
                          static_cast<size_t>(center->size()) == idx_q.size() &&
                          idx_v.size() == idx_q.size(),
                      "ObjectiveConfig: joint_centering needs idx_q, idx_v, center and "
                      "half_range of one size");
            }
            require(k != ObjectiveKind::posture || q_ref,
                    "ObjectiveConfig: posture needs q_ref (nq,)");
            new (self) ObjectiveConfig{k,
                                       gain,
                                       level,
                                       std::move(idx_q),
                                       std::move(idx_v),
                                       center.value_or(Vec()),
                                       half_range.value_or(Vec()),
                                       q_ref.value_or(Vec())};
          },
          nb::arg("kind"), nb::arg("gain"), nb::arg("level"),
          nb::arg("idx_q") = std::vector<int>{}, nb::arg("idx_v") = std::vector<int>{},
          nb::arg("center") = nb::none(), nb::arg("half_range") = nb::none(),
          nb::arg("q_ref") = nb::none())
      .def_ro("gain", &ObjectiveConfig::gain)
      .def_ro("level", &ObjectiveConfig::level);
}

void bind_configs(nb::module_& m) {
  bind_goals(m);
  nb::class_<TaskConfig>(m, "TaskConfig", "The task: its frame and rows (clik.Task).")
      .def(nb::init<int, std::vector<int>, bool, bool>(), nb::kw_only(), nb::arg("frame"),
           nb::arg("rows"), nb::arg("has_position"), nb::arg("has_orientation"))
      .def_ro("frame", &TaskConfig::frame)
      .def_ro("rows", &TaskConfig::rows)
      .def_ro("has_position", &TaskConfig::has_position)
      .def_ro("has_orientation", &TaskConfig::has_orientation);
  nb::class_<LawConfig>(m, "LawConfig", "The law, the task's gains and the extended task's room.")
      .def(
          "__init__",
          [](LawConfig* self, const std::string& law, double damping, double dt, double beta_max,
             const Vec& K_task, int rows, double alpha, const std::optional<Vec>& vmax,
             const std::optional<Vec>& amax, const std::optional<std::vector<int>>& levels,
             const std::vector<ObjectiveConfig>& objectives) {
            require(finite_positive(dt), "LawConfig: dt a finite time > 0 [s]");
            require(finite_nonnegative(damping), "LawConfig: damping finite >= 0");
            require(finite_positive(beta_max), "LawConfig: beta_max finite > 0 [1/s]");
            require(finite_positive(alpha), "LawConfig: alpha finite > 0 [1/s]");
            require(rows >= 1 && K_task.size() >= 1,
                    "LawConfig: rows >= 1 and K_task, a gain per task row (at least one)");
            const LawKind kind = law_kind(law);
            if (levels) {
              bool ok = !levels->empty() && levels->front() >= 1 &&
                        levels->back() == static_cast<int>(K_task.size());
              for (size_t l = 1; ok && l < levels->size(); ++l) {
                ok = (*levels)[l] > (*levels)[l - 1];
              }
              require(ok, "LawConfig: levels, the end row of each level, strictly increasing, "
                          "the last == len(K_task)");
            }
            require(kind == LawKind::pseudoinverse ||
                        ((!levels || levels->size() == 1) && objectives.empty()),
                    "LawConfig: levels and objectives need law 'pseudoinverse'");
            // objectives' levels and data are checked against the model where the run is built.
            // vmax and amax are checked against the model where the run is built.
            SpeedBounds speed{vmax.value_or(Vec()), amax.value_or(Vec())};
            const bool budget_blocks = speed.velocity.size() == 0;
            new (self) LawConfig{LawSettings{kind, damping, dt, beta_max, budget_blocks},
                                 K_task,
                                 rows,
                                 alpha,
                                 std::move(speed),
                                 levels.value_or(std::vector<int>{}),
                                 objectives};
          },
          nb::kw_only(), nb::arg("law"), nb::arg("damping"), nb::arg("dt"), nb::arg("beta_max"),
          nb::arg("K_task"), nb::arg("rows"), nb::arg("alpha"), nb::arg("vmax") = nb::none(),
          nb::arg("amax") = nb::none(), nb::arg("levels") = nb::none(),
          nb::arg("objectives") = std::vector<ObjectiveConfig>{})
      .def_ro("levels", &LawConfig::levels)
      .def_prop_ro("dt", [](const LawConfig& c) { return c.settings.dt; })
      .def_ro("K_task", &LawConfig::K_task)
      .def_ro("rows", &LawConfig::rows)
      .def_ro("alpha", &LawConfig::alpha)
      .def_prop_ro("vmax", [](const LawConfig& c) { return c.speed.velocity; })
      .def_prop_ro("amax", [](const LawConfig& c) { return c.speed.acceleration; });
  nb::class_<StopConfig>(m, "StopConfig", "The stop checks' settings (clik.loop.stop_checks).")
      .def(
          "__init__",
          [](StopConfig* self, double deadlock_window, double deadlock_ratio,
             double deadlock_error, double max_joint_step, double stall_window,
             double stall_progress) {
            // The windows are checked against dt where the run is built (require_window).
            require(finite_positive(deadlock_window) && finite_positive(stall_window),
                    "StopConfig: deadlock_window and stall_window finite times > 0 [s]");
            require(finite_nonnegative(deadlock_ratio) && finite_nonnegative(deadlock_error) &&
                        max_joint_step > 0.0 && std::isfinite(stall_progress),
                    "StopConfig: deadlock_ratio and deadlock_error finite >= 0, max_joint_step "
                    "> 0 [rad or m], stall_progress finite");
            new (self) StopConfig{deadlock_window, deadlock_ratio, deadlock_error,
                                  max_joint_step,  stall_window,   stall_progress};
          },
          nb::kw_only(), nb::arg("deadlock_window"), nb::arg("deadlock_ratio"),
          nb::arg("deadlock_error"), nb::arg("max_joint_step"), nb::arg("stall_window"),
          nb::arg("stall_progress"))
      .def_ro("deadlock_window", &StopConfig::deadlock_window)
      .def_ro("deadlock_ratio", &StopConfig::deadlock_ratio)
      .def_ro("deadlock_error", &StopConfig::deadlock_error)
      .def_ro("max_joint_step", &StopConfig::max_joint_step)
      .def_ro("stall_window", &StopConfig::stall_window)
      .def_ro("stall_progress", &StopConfig::stall_progress);
  nb::class_<JointMonitorConfig>(m, "JointMonitorConfig",
                                 "The joint limits a run must stay in (violations).")
      .def(
          "__init__",
          [](JointMonitorConfig* self, std::vector<int> index, const Vec& lower, const Vec& upper,
             std::vector<std::string> names) {
            const auto n = static_cast<Eigen::Index>(index.size());
            if (lower.size() != n || upper.size() != n ||
                static_cast<Eigen::Index>(names.size()) != n) {
              throw std::invalid_argument(
                  "JointMonitorConfig: lower, upper and names need one entry per index");
            }
            for (Eigen::Index i = 0; i < n; ++i) {
              require(!std::isnan(lower[i]) && !std::isnan(upper[i]) && lower[i] <= upper[i],
                      "JointMonitorConfig: limits not NaN, lower <= upper");
            }
            new (self) JointMonitorConfig{std::move(index), lower, upper, std::move(names)};
          },
          nb::kw_only(), nb::arg("index"), nb::arg("lower"), nb::arg("upper"), nb::arg("names"))
      .def_ro("index", &JointMonitorConfig::index)
      .def_ro("lower", &JointMonitorConfig::lower)
      .def_ro("upper", &JointMonitorConfig::upper)
      .def_ro("names", &JointMonitorConfig::names);
}

// What a controller reads after each tick of an open run (any run has them).
void bind_session(nb::class_<PyTrackingRun>& run) {
  run.def_prop_ro("next", [](const PyTrackingRun& s) { return s.next; },
                  "The sample the next advance() starts at.")
      .def_prop_ro("open", [](const PyTrackingRun& s) { return s.run->is_open(); })
      .def_prop_ro("notes", [](const PyTrackingRun& s) { return s.run->monitor().notes(); },
                   "Limit crossings noted so far (compare before and after a sample).")
      .def_prop_ro("last_orientation_error",
                   [](const PyTrackingRun& s) { return s.run->last_orientation_error(); },
                   "The primary task's orientation rows' error norm at the last sample [rad].")
      .def(
          "move_obstacle",
          [](PyTrackingRun& s, const std::string& name, const Vec3& position,
             const Vec3& velocity, const Mat3& rotation) {
            require(position.allFinite() && velocity.allFinite() && rotation.allFinite(),
                    "move_obstacle: finite position, velocity [m, m/s] and rotation");
            const double tk = s.run->time(s.next);  // from the next sample on
            if (!s.constraints ||
                !s.constraints->move_obstacle(name, position, velocity, rotation, tk)) {
              throw std::invalid_argument("move_obstacle: no obstacle named '" + name + "'");
            }
          },
          nb::arg("name"), nb::arg("position"), nb::arg("velocity"), nb::arg("rotation"),
          "Obstacle `name` at `position` [m] at the next sample's time, moving with "
          "`velocity` [m/s] from then on, rotated by `rotation` (3, 3).")
      .def(
          "replace_cloud",
          [](PyTrackingRun& s, const CloudConfig& cloud) {
            if (!s.constraints || !s.constraints->replace_cloud(cloud)) {
              throw std::invalid_argument("replace_cloud: no cloud named '" + cloud.name + "'");
            }
          },
          nb::arg("cloud"),
          "Cloud `cloud.name` replaced by `cloud` (a checked CloudConfig) from the next sample.")
      .def_prop_ro("active_names",
                   [](const PyTrackingRun& s) {
                     return s.constraints ? s.constraints->active_names()
                                          : std::vector<std::string>{};
                   },
                   "The constraints active now, in row order ([] without constraints).");
}

}  // namespace

void bind_tracking(nb::module_& m) {
  m.attr("BLOCKED_FRACTION") = BLOCKED_FRACTION;
  m.attr("STABILITY_EVERY") = STABILITY_EVERY;
  m.attr("JOINT_TOLERANCE") = JOINT_TOLERANCE;
  bind_configs(m);
  bind_record(m);
  nb::class_<PyTrackingRun> run(m, "TrackingRun");
  bind_session(run);
  run
      .def("__init__", &make_run, nb::kw_only(), nb::arg("model"), nb::arg("task"),
           nb::arg("law"), nb::arg("stop"), nb::arg("t").noconvert().none() = nb::none(),
           nb::arg("t0") = 0.0, nb::arg("record"), nb::arg("joints"),
           nb::arg("constraints").none(), nb::arg("goals") = std::vector<GoalConfig>{},
           nb::arg("events") = 0L,
           "model: the robot's pin.Model (borrowed); t: the time grid (N,) float64, read in "
           "place, or None: an open run (a controller's ticks, advance(k, k + 1), no last "
           "sample; times t0 + k dt; record a RecordArrays(ring=True)); record: the "
           "Recorder's arrays; constraints: a ConstraintSetConfig or None; events: the "
           "constraint events kept, the last ones (0: every one).")
      .def("advance", &advance, nb::arg("c0"), nb::arg("c1"), nb::arg("P_d").noconvert().none(),
           nb::arg("R_d").noconvert().none(), nb::arg("FF").noconvert(),
           nb::arg("at_rest").noconvert(), nb::arg("q").noconvert(),
           nb::arg("goal_ref").noconvert().none() = nb::none(),
           nb::arg("goal_ff").noconvert().none() = nb::none(),
           "Run samples [c0, c1): (next, stop, k, r, err); q is updated in place. With goals: "
           "goal_ref (c1 - c0, D) and goal_ff (c1 - c0, M). An open run goes on after a stop "
           "at k (next = k + 1): q_{k+1} after a deadlock or a stall, q_k held after a "
           "divergence.")
      .def_prop_ro("goal_max", [](const PyTrackingRun& s) { return Mat(s.run->goal_max()); })
      .def_prop_ro("goal_last", [](const PyTrackingRun& s) { return Mat(s.run->goal_last()); })
      .def_prop_ro("max_error", [](const PyTrackingRun& s) { return s.run->max_error(); })
      .def_prop_ro("last_error", [](const PyTrackingRun& s) { return s.run->last_error(); })
      .def_prop_ro("steps", [](const PyTrackingRun& s) { return s.run->steps(); })
      .def_prop_ro("kept", [](const PyTrackingRun& s) { return s.run->kept(); })
      .def_prop_ro("qdot", [](const PyTrackingRun& s) { return Vec(s.run->qdot()); })
      .def_prop_ro("jump", [](const PyTrackingRun& s) { return s.run->checks().jump; })
      .def_prop_ro("margin", [](const PyTrackingRun& s) { return s.run->checks().margin; })
      .def_prop_ro("worst_margin",
                   [](const PyTrackingRun& s) { return s.run->checks().worst_margin; })
      .def_prop_ro("ext_J", [](const PyTrackingRun& s) { return Mat(s.run->extended().J); })
      .def_prop_ro("ext_e", [](const PyTrackingRun& s) { return Vec(s.run->extended().e); })
      .def_prop_ro("ext_K", [](const PyTrackingRun& s) { return Vec(s.run->extended().K); })
      .def_prop_ro("ext_ff", [](const PyTrackingRun& s) { return Vec(s.run->extended().ff); })
      .def("constraint_records",
           [](const PyTrackingRun& s) {
             if (!s.constraints) throw std::invalid_argument("the run has no constraints");
             const long kept = std::min(s.run->kept(), s.record.capacity());  // a ring's slots
             return constraint_records(*s.constraints, static_cast<int>(kept));
           },
           "What the run's constraints recorded (see constraints/bind_constraints.hpp).")
      .def_prop_ro("violations", [](const PyTrackingRun& s) {
        nb::list out;
        for (const auto& v : s.run->monitor().records()) {
          out.append(nb::make_tuple(v.constraint, v.kind, v.t_first, v.t_last, v.worst));
        }
        return out;
      });
  bind_ticker(m);
}

}  // namespace clik
