// The tracking loop: see loop/tracking.hpp and clik/loop/tracking.py (the specification).
#include "loop/tracking.hpp"

#include <cmath>
#include <stdexcept>

#include <pinocchio/algorithm/center-of-mass.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/spatial/explog.hpp>

#include "loop/constraint_hooks.hpp"

namespace clik {

namespace {
constexpr auto LWA = pinocchio::LOCAL_WORLD_ALIGNED;
}

const TaskConfig& TrackingRun::checked(const pinocchio::Model& model, const TaskConfig& task,
                                       const LawConfig& law, const JointMonitorConfig& joints) {
  const auto m = static_cast<int>(task.rows.size());
  bool ok = task.frame >= 0 && task.frame < static_cast<int>(model.nframes) && m >= 1 &&
            m <= MAX_TASK_ROWS;
  for (int row : task.rows) ok = ok && row >= 0 && row < 6;
  if (!ok) {
    throw std::invalid_argument(
        "TrackingRun: the task's frame in the model, 1 to 6 rows among 0..5");
  }
  const auto nv = static_cast<Eigen::Index>(model.nv);
  const Vec& v = law.speed.velocity;
  const Vec& a = law.speed.acceleration;
  bool speed_ok = (v.size() == 0 || v.size() == nv) && (a.size() == 0 || a.size() == nv) &&
                  (a.size() == 0 || v.size() == nv);
  for (Eigen::Index i = 0; speed_ok && i < v.size(); ++i) {
    speed_ok = std::isfinite(v[i]) && v[i] > 0.0;
  }
  for (Eigen::Index i = 0; speed_ok && i < a.size(); ++i) speed_ok = a[i] > 0.0;  // inf: none
  if (!speed_ok) {
    throw std::invalid_argument(
        "LawConfig: vmax, nv finite speeds > 0 [rad/s or m/s] or none; amax, nv accelerations "
        "> 0 [rad/s^2 or m/s^2] (inf: none) or none, and only with vmax");
  }
  for (int i : joints.index) {
    if (i < 0 || i >= model.nq) {
      throw std::invalid_argument("JointMonitorConfig: an index outside the robot's model");
    }
  }
  return task;
}

// The levels' end rows (LawConfig.levels) checked against the rows of the primary task
// (always in the first level) and of the goals (a level holds whole goals).
LevelPlan TrackingRun::level_plan(const pinocchio::Model& model, const TaskConfig& task,
                                  const LawConfig& law, const Goals& goals) {
  const int m0 = static_cast<int>(task.rows.size());
  const int m = m0 + goals.rows();
  if (law.K_task.size() != m || law.rows < m) {
    throw std::invalid_argument(
        "LawConfig: K_task, one gain per task row (the primary's " + std::to_string(m0) +
        " and the goals' " + std::to_string(goals.rows()) + "), and rows >= them");
  }
  LevelPlan plan;
  plan.ends = law.levels.empty() ? std::vector<int>{m} : law.levels;
  bool ok = plan.ends.front() >= m0 && plan.ends.back() == m;
  for (size_t l = 0; ok && l < plan.ends.size(); ++l) {
    const int end = plan.ends[l];
    ok = l == 0 || end > plan.ends[l - 1];
    bool boundary = end == m0;
    for (int g = 0; !boundary && g < goals.count(); ++g) boundary = end == m0 + goals.row_end(g);
    ok = ok && boundary;
  }
  if (!ok) {
    throw std::invalid_argument(
        "LawConfig: levels, the end row of each level, strictly increasing, each at the end "
        "of the primary task or of a goal, the first >= the primary's rows, the last == every "
        "task row (" + std::to_string(m) + ")");
  }
  if (law.settings.kind != LawKind::pseudoinverse &&
      (plan.ends.size() > 1 || !law.objectives.empty())) {
    throw std::invalid_argument(
        "LawConfig: levels and objectives need law 'pseudoinverse' (laws (9) and (8): one "
        "level, no objective)");
  }
  const int L = static_cast<int>(plan.ends.size());
  for (const ObjectiveConfig& o : law.objectives) {
    if (o.level < 1 || o.level > L) {  // checked before the law indexes its levels by it
      throw std::invalid_argument("ObjectiveConfig: level, the level (1 to " +
                                  std::to_string(L) + ") below which the objective acts");
    }
    plan.objective_levels.push_back(o.level);
  }
  plan.lo.assign(static_cast<size_t>(m), model.nv);  // each row's columns (law (10)'s sums)
  plan.hi.assign(static_cast<size_t>(m), 0);
  frame_columns(model, task.frame, plan.lo[0], plan.hi[0]);
  for (int i = 1; i < m0; ++i) {
    plan.lo[static_cast<size_t>(i)] = plan.lo[0];
    plan.hi[static_cast<size_t>(i)] = plan.hi[0];
  }
  goals.columns(model, plan.lo.data() + m0, plan.hi.data() + m0);
  return plan;
}

TrackingRun::TrackingRun(const pinocchio::Model& model, const TaskConfig& task,
                         const LawConfig& law, const StopConfig& stop, const Clock& t,
                         const RecordBuffers& record, JointMonitorConfig joints,
                         ConstraintRun* constraints, const std::vector<GoalConfig>& goals)
    : model_(model), data_(model), task_(checked(model, task, law, joints)),
      goals_(model, goals), m0_(static_cast<int>(task.rows.size())), m_(m0_ + goals_.rows()),
      plan_(level_plan(model, task, law, goals_)), dt_(law.settings.dt), t_(t),
      ext_(m_, law.rows, model.nv, law.K_task),
      law_(law.settings, law.rows, model.nv, m_, plan_),
      objectives_(model, law.objectives, static_cast<int>(plan_.ends.size()), task.frame,
                  task.rows),
      speed_(law.speed, law.settings.dt, model.nv),
      checks_(stop, law.settings.kind, law.settings.dt, law.rows), rec_(record),
      monitor_(std::move(joints)),
      crun_(constraints), J6_(6, model.nv), e6_(Eigen::Matrix<double, 6, 1>::Zero()),
      qdot_(Vec::Zero(model.nv)), dq_(Vec::Zero(model.nv)), qnext_(Vec::Zero(model.nq)),
      qv_(Vec::Zero(model.nq)),
      goal_norms_(Mat::Zero(goals_.count(), 2)), goal_max_(Mat::Zero(goals_.count(), 2)) {
  J6_.setZero();
  for (int row : task.rows) (row < 3 ? pos_rows_ : rot_rows_).push_back(row);
  for (int g = 0; g < goals_.count(); ++g) {
    if (m0_ + goals_.row_end(g) <= plan_.ends.front()) first_goals_ = g + 1;
  }
  full_kinematics_ = crun_ != nullptr || goals_.count() > 0 || !objectives_.empty();
}

// 1. The frame's placement and Jacobian (6, nv) at q, eq. (3), LOCAL_WORLD_ALIGNED.
// With constraints every joint's Jacobian is computed: their rows need them.
void TrackingRun::kinematics(const Vec& q) {
  if (!full_kinematics_) {
    pinocchio::computeFrameJacobian(model_, data_, q, task_.frame, LWA, J6_);
    pinocchio::updateFramePlacement(model_, data_, task_.frame);
    return;
  }
  pinocchio::computeJointJacobians(model_, data_, q);
  if (goals_.needs_com()) com_jacobian(model_, data_);  // from computeJointJacobians' data
  pinocchio::updateFramePlacement(model_, data_, task_.frame);
  for (int f : goals_.frames()) {
    pinocchio::updateFramePlacement(model_, data_, static_cast<pinocchio::FrameIndex>(f));
  }
  // the frame's support columns, the same at every sample (the others stay zero)
  pinocchio::getFrameJacobian(model_, data_, task_.frame, LWA, J6_);
}

// 2. Task error (6) e = (p_d - p, log3(R_d R^T)) and rows of J into the task rows.
void TrackingRun::task_rows(const double* p_d, const double* R_d, const double* xdot_d) {
  const pinocchio::SE3& placement = data_.oMf[task_.frame];
  if (p_d != nullptr && task_.has_position) {
    e6_.head<3>() = Eigen::Map<const Vec3>(p_d) - placement.translation();
  }
  if (R_d != nullptr && task_.has_orientation) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> Rd(R_d);
    const Mat3 R = Rd * placement.rotation().transpose();
    e6_.tail<3>() = pinocchio::log3(R);
  }
  for (int i = 0; i < m0_; ++i) {
    const int row = task_.rows[i];
    ext_.e[i] = e6_[row];
    ext_.J.row(i) = J6_.row(row);
    ext_.ff[i] = xdot_d[i];
  }
}

// Norms of the task's own position rows [m] and orientation rows [rad]; the
// first is the run's task error (the orientation rows' for an orientation task).
void TrackingRun::error_norms(double& pos, double& rot) const {
  double r2 = 0.0, p2 = 0.0;
  for (int row : rot_rows_) r2 += e6_[row] * e6_[row];
  rot = std::sqrt(r2);
  if (pos_rows_.empty()) {
    pos = rot;
    return;
  }
  for (int row : pos_rows_) p2 += e6_[row] * e6_[row];
  pos = std::sqrt(p2);
}

// 5. Why the run must stop at sample k, if it must.
Stop TrackingRun::stop(long k, double err, int r, double blocked, bool at_rest) {
  Stop why = checks_.divergence(qdot_, err);
  if (why == Stop::none) why = checks_.instability(k, ext_, r, err);
  if (why != Stop::none) return why;
  if (checks_.deadlock(ext_, r, err, blocked)) return Stop::deadlock;
  if (checks_.stall(k, err, at_rest)) return Stop::stall;
  return Stop::none;
}

// 6. q_{k+1} = q_k (+) qdot_k dt (pin.integrate), in place.
void TrackingRun::step(Vec& q) {
  dq_ = qdot_ * dt_;
  pinocchio::integrate(model_, q, dq_, qnext_);
  q.swap(qnext_);
}

// Every limit crossed at this sample: joints, obstacle surfaces, link pairs.
void TrackingRun::observe_limits(double tk, const Vec& q) {
  monitor_.observe_joints(tk, q);
  if (crun_ != nullptr) observe_constraint_limits(*crun_, tk, monitor_);
}

Advance TrackingRun::advance(long c0, long c1, const double* P_d, const double* R_d,
                             const double* FF, const bool* at_rest, Eigen::Ref<Vec> q,
                             const double* goal_ref, const double* goal_ff) {
  const long N = t_.size();
  qv_ = q;  // the state as a Vec (its storage reused: nothing allocated per call)
  if (!started_) {
    rec_.start(qv_);
    started_ = true;
  }
  Advance out;
  for (long k = c0; k < c1; ++k) {
    const long kk = k - c0;
    const double* p_d = P_d == nullptr ? nullptr : P_d + 3 * kk;
    kinematics(qv_);
    task_rows(p_d, R_d == nullptr ? nullptr : R_d + 9 * kk, FF + m0_ * kk);
    if (goals_.count() > 0) {
      goals_.write(GoalContext{model_, data_, qv_}, goal_ref + goals_.ref_size() * kk,
                   goal_ff + goals_.ff_size() * kk, ext_, m0_);
    }
    if (!objectives_.empty()) {
      objectives_.compute(model_, data_, qv_, ext_.J.topRows(m0_), law_.objective_z());
    }
    const bool exact = rec_.due(k);
    const int r = crun_ == nullptr
                      ? m_
                      : m_ + update_constraints(*crun_, k, qv_, model_, data_, ext_, law_, exact);
    const double blocked = law_.velocity(ext_, r, qdot_);
    if (speed_.enabled()) {
      if (law_.by_levels()) {
        speed_.apply_levels(law_.parts(), qdot_);
      } else {
        const bool level = law_.settings().kind == LawKind::pseudoinverse;
        speed_.apply(ext_, r, level ? &law_.constraint_part() : nullptr, qdot_);
      }
    }
    double err = 0.0, err_rot = 0.0;
    error_norms(err, err_rot);
    err_ = err;
    err_rot_ = err_rot;
    max_err_ = std::max(max_err_, err);
    double err_stop = err;
    if (goals_.count() > 0) {
      goals_.norms(ext_, m0_, goal_norms_);
      for (int g = 0; g < goals_.count(); ++g) {
        for (int c = 0; c < 2; ++c) {  // a NaN carries through
          if (!(goal_norms_(g, c) <= goal_max_(g, c))) goal_max_(g, c) = goal_norms_(g, c);
        }
        if (g < first_goals_ && !(goal_norms_(g, 0) <= err_stop)) err_stop = goal_norms_(g, 0);
      }
    }
    const Stop why = stop(k, err_stop, r, blocked, at_rest[kk]);
    observe_limits(t_[k], qv_);
    if (exact || why != Stop::none) {
      const long j = rec_.keep(k, qv_, qdot_, data_.oMf[task_.frame].translation(), p_d, err,
                               err_rot);
      if (crun_ != nullptr) record_constraints(*crun_, rec_, j, r - m_);
      if (goals_.count() > 0) rec_.goals(j, goal_norms_);
    }
    rec_.every_sample(qv_, qdot_);
    steps_ = k + 1;
    if (why != Stop::none) {
      out.next = k + 1;
      out.stop = why;
      out.k = k;
      out.r = r;
      out.err = err_stop;
      // an open run goes on: past a deadlock or a stall as usual; a divergence holds q_k
      if (t_.is_open() && (why == Stop::deadlock || why == Stop::stall)) step(qv_);
      q = qv_;
      return out;
    }
    if (k + 1 < N) step(qv_);  // always in an open run (N: LONG_MAX)
  }
  out.next = c1;
  q = qv_;
  return out;
}

}  // namespace clik
