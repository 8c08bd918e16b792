// One run's constraints: see constraint_run.hpp and clik/constraints/constraint_run.py
// (the specification: each method below names its Python counterpart).
#include "constraints/constraint_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <stdexcept>
#include <utility>

#include <pinocchio/algorithm/joint-configuration.hpp>

#include "constraints/obstacle_rows.hpp"

namespace clik {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

// Python's round(x, 9): the exact binary value correctly rounded to 9 decimals, read back.
double round9(double x) {
  if (!std::isfinite(x)) return x;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9f", x);
  return std::strtod(buf, nullptr);
}

}  // namespace

const char* action_name(EventAction action) {
  switch (action) {
    case EventAction::activate:
      return "activate";
    case EventAction::release:
      return "release";
    case EventAction::skipped:
      return "skipped";
  }
  return "";
}

ConstraintRun::ConstraintRun(const ConstraintConfig& config, const pinocchio::Model& model, int m,
                             LawKind law, double alpha, const TimesView& t, int n_rec, int frame,
                             std::vector<int> task_rows)
    : cfg_(config), model_(model), m_(m), law_(law), alpha_(alpha), t_(t) {
  if (model.nv != cfg_.nv || model.nq != cfg_.nq) {
    throw std::invalid_argument("ConstraintRun: the model is not the constraint set's robot");
  }
  limit_ = cfg_.row_limit(m, law);
  const int nv = model.nv;
  n_obs_ = cfg_.n_obstacles();
  n_links_ = cfg_.n_links();
  n_self_ = cfg_.n_self();
  n_joint_rows_ = cfg_.joint_limits ? 2 * cfg_.joint_limits->n : 0;
  obstacle_base_ = n_joint_rows_;
  self_base_ = obstacle_base_ + n_links_ * n_obs_;
  if (n_obs_ > 0 && (!cfg_.scene || n_links_ == 0)) {
    throw std::invalid_argument("ConstraintRun: obstacles without link geometry to check");
  }

  // Names, once: key = joint row | obstacle_base + i * n_obs + o | self_base + self pair
  // | dexterity (the last).
  names_.reserve(self_base_ + n_self_ + 1);
  for (int i = 0; i < n_joint_rows_; ++i) names_.push_back(cfg_.joint_limits->names[i]);
  for (int i = 0; i < n_links_; ++i) {
    for (int o = 0; o < n_obs_; ++o) names_.push_back(cfg_.pair_name(i, o));
  }
  for (int s = 0; s < n_self_; ++s) names_.push_back(cfg_.self_name(s));
  if (cfg_.dexterity) {
    if (frame < 0 || static_cast<int>(task_rows.size()) != m) {
      throw std::invalid_argument("ConstraintRun: the dexterity row needs the task's frame and rows");
    }
    dexterity_key_ = static_cast<int>(names_.size());
    names_.push_back("dexterity");
    dex_.emplace(model, frame, std::move(task_rows));
  }
  const int n_keys = static_cast<int>(names_.size());

  if (cfg_.scene) scene_.emplace(*cfg_.scene, cfg_.obstacles);

  const int active_room = std::max(limit_, 0);
  cand_.reserve(n_keys);
  active_.reserve(active_room);
  still_.reserve(active_room);
  fresh_.reserve(n_keys);
  marked_.reserve(active_room);
  cur_index_.assign(n_keys, -1);
  is_active_.assign(n_keys, 0);
  skipped_.assign(n_keys, 0);
  in_fresh_.assign(n_keys, 0);
  skipped_list_.reserve(n_keys);
  todo_.reserve(n_links_ * n_obs_ + active_room);
  close_.reserve(n_self_);
  self_penetrations.reserve(n_self_);
  qdot_ = Vec::Zero(nv);

  q_prev_ = Vec::Zero(model.nq);
  dq_ = Vec::Zero(nv);
  joint_e_ = Vec::Zero(n_joint_rows_);
  lb_ = Eigen::MatrixXd::Constant(n_links_, n_obs_, -INF);
  evaluated_.assign(static_cast<size_t>(n_links_) * n_obs_, 0);
  rho_dq_ = Vec::Zero(n_links_);
  thr_o_ = Vec::Zero(n_obs_);
  margin_o_ = Vec::Zero(n_obs_);
  obs_step_ = Vec::Zero(n_obs_);
  const double dt = t_.size() > 1 ? t_[1] - t_[0] : 0.0;
  for (int o = 0; o < n_obs_; ++o) {
    const ObstacleConfig& ob = cfg_.obstacles[o];
    thr_o_[o] = ob.threshold;
    margin_o_[o] = ob.threshold + cfg_.monitor_margin;
    const Vec3& v = ob.velocity;
    obs_step_[o] = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt;
    has_obs_step_ = has_obs_step_ || obs_step_[o] > 0.0;
  }
  if (n_links_ > 0 && (cfg_.rho.rows() != n_links_ || cfg_.rho.cols() != nv)) {
    throw std::invalid_argument("ConstraintRun: rho is not (n_links, nv)");
  }
  J6a_ = pinocchio::Data::Matrix6x::Zero(6, nv);
  J6b_ = pinocchio::Data::Matrix6x::Zero(6, nv);
  Jp_ = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, nv);

  dist_o = Vec::Constant(n_obs_, INF);
  exact_o.assign(n_obs_, 0);
  link_o = Eigen::VectorXi::Constant(n_obs_, -1);
  events_.reserve(256);
  code_of_key_.assign(n_keys, -1);
  code_keys_.reserve(n_keys);
  slots_ = std::max(limit_, 1);
  rec_dist_ = Mat::Constant(n_rec, n_obs_, INF);
  rec_link_.setConstant(n_rec, n_obs_, -1);
  rec_active_.setConstant(n_rec, slots_, -1);
  rec_witness_ = Mat::Constant(n_rec, slots_ * 6, std::numeric_limits<double>::quiet_NaN());
  run_min_ = Vec::Constant(n_obs_, INF);
  run_min_t_ = Vec::Zero(n_obs_);
  run_min_link_.assign(n_obs_, -1);
}

// -- per sample ------------------------------------------------------------------------

int ConstraintRun::update(int k, const Eigen::Ref<const Vec>& q, pinocchio::Data& data,
                          ExtendedTask& ext, Law& law, bool exact) {
  const double tk = t_[k];
  placed_ = false;
  evaluate(tk, q, data, exact);
  if (dex_) evaluate_dexterity(ext);
  q_prev_ = q;
  has_prev_ = true;
  refresh_active(tk);
  activate(tk);
  int v = fill_rows(data, ext);
  if (cfg_.release == ReleaseRule::projection && v) v = project_release(tk, ext, law, v);
  return v;
}

void ConstraintRun::mark_active() {
  for (int key : marked_) is_active_[key] = 0;
  marked_.clear();
  for (const Candidate& c : active_) {
    is_active_[c.key] = 1;
    marked_.push_back(c.key);
  }
}

// _refresh_active: refresh the active constraints' data; release those the sign rule lets go.
void ConstraintRun::refresh_active(double tk) {
  for (int i = 0; i < static_cast<int>(cand_.size()); ++i) cur_index_[cand_[i].key] = i;
  still_.clear();
  const bool sign = cfg_.release == ReleaseRule::sign;
  for (const Candidate& c : active_) {
    const int idx = cur_index_[c.key];
    if (idx < 0) {  // no longer evaluated: far from its threshold
      event(tk, c.key, EventAction::release);
    } else if (sign && cand_[idx].error < -cfg_.hysteresis * cand_[idx].scale) {
      event(tk, c.key, EventAction::release);
    } else {
      still_.push_back(cand_[idx]);
    }
  }
  for (const Candidate& c : cand_) cur_index_[c.key] = -1;
  active_.swap(still_);
}

// _activate: the most violated first, within the bound on active rows (22).
void ConstraintRun::activate(double tk) {
  mark_active();
  fresh_.clear();
  for (int i = 0; i < static_cast<int>(cand_.size()); ++i) {
    const Candidate& c = cand_[i];
    if (!is_active_[c.key] && c.error > AT_THRESHOLD * c.scale) fresh_.push_back(i);
  }
  // sorted(..., key=-error / scale): stable, so an insertion sort (allocates nothing).
  for (size_t a = 1; a < fresh_.size(); ++a) {
    const int idx = fresh_[a];
    const double key = -cand_[idx].error / cand_[idx].scale;
    size_t b = a;
    while (b > 0 && key < -cand_[fresh_[b - 1]].error / cand_[fresh_[b - 1]].scale) {
      fresh_[b] = fresh_[b - 1];
      --b;
    }
    fresh_[b] = idx;
  }
  for (int idx : fresh_) {
    const Candidate& c = cand_[idx];
    if (static_cast<int>(active_.size()) < limit_) {
      active_.push_back(c);
      event(tk, c.key, EventAction::activate);
      skipped_[c.key] = 0;  // discard (the list is pruned below)
    } else if (!skipped_[c.key]) {
      skipped_[c.key] = 1;
      skipped_list_.push_back(c.key);
      event(tk, c.key, EventAction::skipped);
    }
  }
  if (!skipped_list_.empty()) {  // skipped &= {fresh keys}
    for (int idx : fresh_) in_fresh_[cand_[idx].key] = 1;
    size_t w = 0;
    for (int key : skipped_list_) {
      if (skipped_[key] && in_fresh_[key]) {
        skipped_list_[w++] = key;
      } else {
        skipped_[key] = 0;
      }
    }
    skipped_list_.resize(w);
    for (int idx : fresh_) in_fresh_[cand_[idx].key] = 0;
  }
}

// -- evaluation ------------------------------------------------------------------------

// _evaluate: constraints whose error is positive, or that are active, at this sample.
void ConstraintRun::evaluate(double tk, const Eigen::Ref<const Vec>& q, pinocchio::Data& data,
                             bool exact) {
  mark_active();
  cand_.clear();
  if (!has_prev_) {
    dq_valid_ = false;
  } else {  // |dq| since the last sample, for the joint and obstacle certificates
    pinocchio::difference(model_, q_prev_, q, dq_);
    dq_ = dq_.cwiseAbs();
    dq_valid_ = true;
  }
  if (cfg_.joint_limits) evaluate_joints(q);
  if (scene_) {
    if (n_obs_) evaluate_obstacles(tk, data, exact);
    if (n_self_) evaluate_self(tk, data);
  }
}

// _evaluate_joints: joint-range errors (17), behind a certificate.
void ConstraintRun::evaluate_joints(const Eigen::Ref<const Vec>& q) {
  const JointLimits& jl = *cfg_.joint_limits;
  if (dq_valid_ && dq_.size()) joint_slack_ -= dq_.maxCoeff();
  bool joint_active = false;
  for (const Candidate& c : active_) joint_active = joint_active || c.kind == ConstraintKind::joint;
  if (joint_slack_ > 0.0 && !joint_active) return;
  jl.evaluate(q, joint_e_);
  joint_slack_ = joint_e_.size() ? -joint_e_.maxCoeff() : INF;
  const Vec& thr = jl.row_threshold;
  for (int i = 0; i < n_joint_rows_; ++i) {
    const double e = joint_e_[i];
    if (e > -thr[i] && (e > 0.0 || is_active_[i])) {
      Candidate c;
      c.key = i;
      c.kind = ConstraintKind::joint;
      c.error = e;
      c.scale = c.threshold = thr[i];
      c.index = i;
      cand_.push_back(c);
    }
  }
}

void ConstraintRun::place(double tk, const pinocchio::Data& data) {
  if (!placed_) {
    scene_->place_geometries(model_, data, tk);
    placed_ = true;
  }
}

// _evaluate_obstacles: link-obstacle pairs through distance certificates.
void ConstraintRun::evaluate_obstacles(double tk, pinocchio::Data& data, bool exact) {
  if (dq_valid_) {
    rho_dq_.noalias() = cfg_.rho * dq_;
    lb_.colwise() -= rho_dq_;
    if (has_obs_step_) lb_.rowwise() -= obs_step_.transpose();
  }
  std::fill(evaluated_.begin(), evaluated_.end(), 0);
  todo_.clear();
  for (int i = 0; i < n_links_; ++i) {  // row-major, as np.argwhere
    for (int o = 0; o < n_obs_; ++o) {
      if (lb_(i, o) < thr_o_[o]) todo_.emplace_back(i, o);
    }
  }
  for (const Candidate& c : active_) {
    if (c.kind == ConstraintKind::obstacle) todo_.emplace_back(c.link, c.obstacle);
  }
  Candidate c;
  for (const auto& [i, o] : todo_) {  // the pairs near their threshold, and the active
    char& done = evaluated_[static_cast<size_t>(i) * n_obs_ + o];
    if (done) continue;
    place(tk, data);
    obstacle_candidate(i, o, c);
    lb_(i, o) = c.distance;
    done = 1;
    if (cfg_.obstacle_rows && (c.distance < c.threshold || is_active_[c.key])) {
      cand_.push_back(c);
    }
  }
  // Then each obstacle's nearest link (the first smallest bound, as np.argmin), until
  // it is exact or beyond the margin. A pair evaluated here is at or beyond its
  // threshold (its bound was), so it is never a candidate.
  for (int o = 0; o < n_obs_; ++o) {
    const double margin = exact ? INF : margin_o_[o];
    while (true) {
      Eigen::Index best;
      dist_o[o] = lb_.col(o).minCoeff(&best);
      link_o[o] = static_cast<int>(best);
      char& known = evaluated_[static_cast<size_t>(best) * n_obs_ + o];
      exact_o[o] = known;
      if (known || !(dist_o[o] < margin)) break;
      place(tk, data);
      obstacle_candidate(static_cast<int>(best), o, c);
      lb_(best, o) = c.distance;
      known = 1;
    }
  }
  double nearest = INF;
  for (int o = 0; o < n_obs_; ++o) {
    const double d = exact_o[o] ? dist_o[o] : INF;
    nearest = std::min(nearest, d);
    if (d < run_min_[o]) {
      run_min_[o] = d;
      run_min_t_[o] = tk;
      run_min_link_[o] = link_o[o];
    }
  }
  min_distance = nearest;
}

// _obstacle_candidate: distance, witness points and error of link geometry i and obstacle o.
void ConstraintRun::obstacle_candidate(int i, int o, Candidate& c) {
  scene_->distance(cfg_.scene->obstacle_pairs(i, o), pd_);
  const double thr = thr_o_[o];
  const ErrorScale es = obstacle_error(cfg_.form, thr, pd_.distance);
  c.key = obstacle_base_ + i * n_obs_ + o;
  c.kind = ConstraintKind::obstacle;
  c.error = es.error;
  c.scale = es.scale;
  c.threshold = thr;
  c.feed = 0.0;
  c.index = -1;
  c.joint = cfg_.scene->link_joint[i];
  c.joint_b = -1;
  c.distance = pd_.distance;
  c.obstacle = o;
  c.link = i;
  c.point_a = pd_.point_a;
  c.point_b = pd_.point_b;
  c.normal = pd_.normal;
}

// _evaluate_self: link-link pairs whose bounding spheres are near, with coal.
void ConstraintRun::evaluate_self(double tk, pinocchio::Data& data) {
  const SceneConfig& sc = *cfg_.scene;
  const auto& pos = scene_->place_joints(data);
  const Vec& r = sc.joint_radius;
  const double reach = cfg_.self_threshold + cfg_.monitor_margin;
  close_.clear();
  for (int idx = 0; idx < n_self_; ++idx) {
    const int a = sc.link_slot[sc.self_pairs[idx].a], b = sc.link_slot[sc.self_pairs[idx].b];
    const double dx = pos(a, 0) - pos(b, 0), dy = pos(a, 1) - pos(b, 1), dz = pos(a, 2) - pos(b, 2);
    const double gap = std::sqrt(dx * dx + dy * dy + dz * dz) - r[a] - r[b];
    if (gap < reach) close_.push_back(idx);
  }
  if (!close_.empty()) place(tk, data);
  self_penetrations.clear();
  const double thr = cfg_.self_threshold;
  for (int idx : close_) {
    const auto& sp = sc.self_pairs[idx];
    scene_->distance(sp.pair, pd_);
    const int key = self_base_ + idx;
    if (pd_.distance < 0.0) self_penetrations.emplace_back(key, pd_.distance);
    if (pd_.distance < thr || is_active_[key]) {
      Candidate c;
      c.key = key;
      c.kind = ConstraintKind::self;
      c.error = thr - pd_.distance;
      c.scale = c.threshold = thr;
      c.joint = sc.link_joint[sp.a];
      c.joint_b = sc.link_joint[sp.b];
      c.distance = pd_.distance;
      c.point_a = pd_.point_a;
      c.point_b = pd_.point_b;
      c.normal = pd_.normal;
      cand_.push_back(c);
    }
  }
}

// _evaluate_dexterity: the error (D2) of the task rows; a candidate when positive or active.
void ConstraintRun::evaluate_dexterity(const ExtendedTask& ext) {
  const double thr = cfg_.dexterity->threshold;
  manipulability = dex_->evaluate(ext.J.topRows(m_));
  const double e = thr - manipulability;
  if (e > 0.0 || is_active_[dexterity_key_]) {
    Candidate c;
    c.key = dexterity_key_;
    c.kind = ConstraintKind::dexterity;
    c.error = e;
    c.scale = c.threshold = thr;
    cand_.push_back(c);
  }
}

// -- rows ------------------------------------------------------------------------------

// _gain: the user's, else alpha (law (10)) or alpha / (2 max(1, |j|^2)).
double ConstraintRun::gain(ConstraintKind kind, double row_norm2) const {
  const std::optional<double>& given = kind == ConstraintKind::obstacle  ? cfg_.obstacle_gain
                                       : kind == ConstraintKind::joint     ? cfg_.joint_gain
                                       : kind == ConstraintKind::dexterity ? cfg_.dexterity_gain
                                                                           : cfg_.self_gain;
  if (given) return *given;
  if (law_ == LawKind::pseudoinverse) return alpha_;
  return 0.5 * alpha_ / std::max(1.0, row_norm2);
}

// _fill_rows: the active constraints' rows (15), (19), (D3) into the extended task (24)-(25).
int ConstraintRun::fill_rows(pinocchio::Data& data, ExtendedTask& ext) {
  static const Vec3 still = Vec3::Zero();
  for (int s = 0; s < static_cast<int>(active_.size()); ++s) {
    Candidate& c = active_[s];
    auto row = ext.J.row(m_ + s);
    if (c.kind == ConstraintKind::joint) {
      cfg_.joint_limits->row(c.index, row);
      c.feed = 0.0;
    } else if (c.kind == ConstraintKind::dexterity) {
      dex_->gradient(model_, data, row);
      c.feed = 0.0;
    } else {  // obstacle (13)-(15), or a link pair: the second link in the obstacle's place
      point_jacobian(model_, data, c.joint, c.point_a, J6a_);
      Jp_ = J6a_.topRows<3>();
      ObstacleForm form = ObstacleForm::normalized;
      const Vec3* velocity = &still;
      if (c.kind == ConstraintKind::obstacle) {
        form = cfg_.form;
        velocity = &cfg_.obstacles[c.obstacle].velocity;
      } else {
        point_jacobian(model_, data, c.joint_b, c.point_b, J6b_);
        Jp_ -= J6b_.topRows<3>();
      }
      const RowTerms rt = obstacle_row(form, c.threshold, c.distance, c.point_a, c.point_b,
                                       c.normal, Jp_, *velocity, row);
      c.error = rt.error;
      c.feed = rt.feed;
    }
    ext.e[m_ + s] = c.error;
    ext.ff[m_ + s] = c.feed;
    ext.K[m_ + s] = gain(c.kind, row.squaredNorm());
  }
  return static_cast<int>(active_.size());
}

// _project_release: release one constraint at its threshold whose row-free solution moves away.
int ConstraintRun::project_release(double tk, ExtendedTask& ext, Law& law, int v) {
  for (int s = 0; s < v; ++s) {
    const Candidate& c = active_[s];
    if (c.error > AT_THRESHOLD * c.scale) continue;
    const int last = m_ + v - 1;
    if (s != v - 1) {  // move this row last, so the law can run without it
      ext.swap(m_ + s, last);
      std::swap(active_[s], active_[v - 1]);
    }
    law.velocity(ext, last, qdot_);
    const double edot = ext.ff[last] - ext.J.row(last).dot(qdot_);
    if (edot <= 0.0) {
      const int key = active_.back().key;
      active_.pop_back();
      event(tk, key, EventAction::release);
      return v - 1;
    }
  }
  return v;
}

void ConstraintRun::event(double tk, int key, EventAction action) {
  events_.push_back({round9(tk), key, action});
}

// -- recording -------------------------------------------------------------------------

void ConstraintRun::record(int j) {
  if (n_obs_) {
    rec_dist_.row(j) = dist_o.transpose();
    rec_link_.row(j) = link_o.transpose().cast<std::int16_t>();
  }
  for (int s = 0; s < static_cast<int>(active_.size()); ++s) {
    const Candidate& c = active_[s];
    int& code = code_of_key_[c.key];
    if (code < 0) {
      code = static_cast<int>(code_keys_.size());
      code_keys_.push_back(c.key);
    }
    rec_active_(j, s) = code;
    if (c.kind == ConstraintKind::obstacle || c.kind == ConstraintKind::self) {
      rec_witness_.block<1, 3>(j, 6 * s) = c.point_a.transpose();
      rec_witness_.block<1, 3>(j, 6 * s + 3) = c.point_b.transpose();
    }
  }
}

std::vector<std::string> ConstraintRun::active_names() const {
  std::vector<std::string> out;
  out.reserve(active_.size());
  for (const Candidate& c : active_) out.push_back(names_[c.key]);
  return out;
}

std::vector<std::string> ConstraintRun::skipped_names() const {
  std::set<std::string> names;
  for (const Event& e : events_) {
    if (e.action == EventAction::skipped) names.insert(names_[e.key]);
  }
  return {names.begin(), names.end()};
}

}  // namespace clik
