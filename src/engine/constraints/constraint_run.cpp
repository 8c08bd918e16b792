// One run's constraints, the core: see constraint_run.hpp and
// clik/constraints/constraint_run.py (the specification: each method below names its
// Python counterpart).
#include "constraints/constraint_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <variant>

#include <pinocchio/algorithm/joint-configuration.hpp>

namespace clik {

namespace {

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

ConstraintRun::ConstraintRun(const ConstraintSetConfig& config, const pinocchio::Model& model,
                             int m, LawKind law, double alpha, const Clock& t, int n_rec,
                             int frame, std::vector<int> task_rows, int task_m, long events)
    : cfg_(config),
      model_(model),
      m_(m),
      task_m_(task_m < 0 ? m : task_m),
      law_(law),
      alpha_(alpha),
      t_(t),
      events_(events) {
  if (cfg_.model == nullptr || model.nv != cfg_.model->nv || model.nq != cfg_.model->nq) {
    throw std::invalid_argument("ConstraintRun: the model is not the constraint set's robot");
  }
  cfg_.require_unchanged();
  limit_ = cfg_.row_limit(m, law);
  if (cfg_.scene) scene_.emplace(*cfg_.scene);

  // The kinds, in the set's order; their keys' names, in the same order.
  const KindSetup base{model,  -1, m, task_m_, t_, n_rec, frame, task_rows, cfg_.monitor_margin,
                       scene_ ? &*scene_ : nullptr};
  kinds_.reserve(cfg_.kinds.size());
  for (const KindConfig& kind : cfg_.kinds) {
    KindSetup setup = base;
    setup.slot = static_cast<int>(kinds_.size());
    std::visit(
        [&](const auto& config) {
          using Run = typename std::decay_t<decltype(config)>::Run;
          kinds_.emplace_back(std::in_place_type<Run>, config, setup);
        },
        kind);
  }
  for (KindRun& kind : kinds_) std::visit([&](auto& k) { k.names(names_); }, kind);
  const int n_keys = static_cast<int>(names_.size());

  const int active_room = std::max(limit_, 0);
  cand_.reserve(n_keys);
  active_.reserve(active_room);
  still_.reserve(active_room);
  fresh_.reserve(n_keys);
  marked_.reserve(active_room);
  cur_index_.assign(n_keys, -1);
  is_active_.assign(n_keys, 0);
  skipped_.assign(n_keys, 0);
  ever_skipped_.assign(n_keys, 0);
  sample_events_.reserve(3 * static_cast<std::size_t>(n_keys));
  in_fresh_.assign(n_keys, 0);
  skipped_list_.reserve(n_keys);
  qdot_ = Vec::Zero(model.nv);
  q_prev_ = Vec::Zero(model.nq);
  dq_ = Vec::Zero(model.nv);

  code_of_key_.assign(n_keys, -1);
  code_keys_.reserve(n_keys);
  slots_ = std::max(limit_, 1);
  rec_active_.setConstant(n_rec, slots_, -1);
  rec_witness_ = Mat::Constant(n_rec, slots_ * 6, std::numeric_limits<double>::quiet_NaN());
}

// -- per sample ------------------------------------------------------------------------

int ConstraintRun::update(long k, const Eigen::Ref<const Vec>& q, pinocchio::Data& data,
                          ExtendedTask& ext, Law& law, bool exact) {
  const double tk = t_[k];
  sample_events_.clear();
  // _evaluate: constraints whose error is positive, or that are active, at this sample.
  mark_active();
  cand_.clear();
  const Vec* dq_abs = nullptr;
  if (has_prev_) {  // |dq| since the last sample, for the kinds' certificates
    pinocchio::difference(model_, q_prev_, q, dq_);
    dq_ = dq_.cwiseAbs();
    dq_abs = &dq_;
  }
  ScenePlacement scene(scene_ ? &*scene_ : nullptr, model_, data, tk);
  Sample s{tk, q, model_, data, dq_abs, ext, m_, task_m_, exact, is_active_, active_, scene};
  min_distance_ = INF;
  for (KindRun& kind : kinds_) {
    std::visit(
        [&](auto& k) {
          k.evaluate(s, cand_);
          const double d = k.min_distance();
          if (!(d >= min_distance_)) min_distance_ = d;  // a NaN carries through
        },
        kind);
  }
  q_prev_ = q;
  has_prev_ = true;
  refresh_active(tk);
  activate(tk);
  int v = fill_rows(s, ext);
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
      ever_skipped_[c.key] = 1;
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

// -- rows ------------------------------------------------------------------------------

// _gain: the kind's, else alpha (law (10)) or alpha / (2 max(1, |j|^2)).
double ConstraintRun::gain(int slot, double row_norm2) const {
  const std::optional<double>& given =
      std::visit([](const auto& k) -> const std::optional<double>& { return k.gain(); },
                 kinds_[slot]);
  if (given) return *given;
  if (law_ == LawKind::pseudoinverse) return alpha_;
  return 0.5 * alpha_ / std::max(1.0, row_norm2);
}

// _fill_rows: the active constraints' rows into the extended task (24)-(25), each by its kind.
int ConstraintRun::fill_rows(Sample& s, ExtendedTask& ext) {
  for (int i = 0; i < static_cast<int>(active_.size()); ++i) {
    Candidate& c = active_[i];
    auto row = ext.J.row(m_ + i);
    std::visit([&](auto& k) { k.row(s, c, row); }, kinds_[c.slot]);
    ext.e[m_ + i] = c.error;
    ext.ff[m_ + i] = c.feed;
    ext.K[m_ + i] = gain(c.slot, row.squaredNorm());
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
  const Event e{round9(tk), key, action};
  events_.push(e);
  sample_events_.push_back(e);
}

// -- limits and records ----------------------------------------------------------------

void ConstraintRun::observe_limits(double tk, ViolationMonitor& monitor) const {
  for (const KindRun& kind : kinds_) {
    std::visit([&](const auto& k) { k.observe_limits(tk, monitor, names_); }, kind);
  }
}

void ConstraintRun::record(int j, bool ring) {
  if (ring) {  // a ring's slot: only the active rows are written below
    rec_active_.row(j).setConstant(-1);
    rec_witness_.row(j).setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  for (KindRun& kind : kinds_) std::visit([&](auto& k) { k.record(j); }, kind);
  for (int s = 0; s < static_cast<int>(active_.size()); ++s) {
    const Candidate& c = active_[s];
    int& code = code_of_key_[c.key];
    if (code < 0) {
      code = static_cast<int>(code_keys_.size());
      code_keys_.push_back(c.key);
    }
    rec_active_(j, s) = code;
    if (c.has_witness) {
      rec_witness_.block<1, 3>(j, 6 * s) = c.point_a.transpose();
      rec_witness_.block<1, 3>(j, 6 * s + 3) = c.point_b.transpose();
    }
  }
}

std::vector<RecordArray> ConstraintRun::kind_records(int slot) const {
  std::vector<RecordArray> out;
  std::visit([&](const auto& k) { k.records(out); }, kinds_.at(slot));
  return out;
}

std::vector<std::string> ConstraintRun::active_names() const {
  std::vector<std::string> out;
  out.reserve(active_.size());
  for (const Candidate& c : active_) out.push_back(names_[c.key]);
  return out;
}

std::vector<std::string> ConstraintRun::skipped_names() const {
  std::set<std::string> names;
  for (std::size_t key = 0; key < ever_skipped_.size(); ++key) {
    if (ever_skipped_[key]) names.insert(names_[key]);
  }
  return {names.begin(), names.end()};
}

bool ConstraintRun::replace_cloud(const CloudConfig& cloud) {
  bool replaced = false;
  for (KindRun& kind : kinds_) {
    replaced = std::visit([&](auto& k) { return k.replace_cloud(cloud); }, kind) || replaced;
  }
  return replaced;
}

bool ConstraintRun::move_obstacle(const std::string& name, const Vec3& position,
                                  const Vec3& velocity, const Mat3& rotation, double tk) {
  bool moved = false;
  for (KindRun& kind : kinds_) {
    const auto move = [&](auto& k) {
      return k.move_obstacle(name, position, velocity, rotation, tk);
    };
    moved = std::visit(move, kind) || moved;
  }
  return moved;
}

}  // namespace clik
