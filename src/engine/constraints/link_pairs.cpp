// Link pairs: see link_pairs.hpp and clik/constraints/link_pairs.py (LinkPairsRun).
#include "constraints/link_pairs.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "constraints/bind_kind.hpp"
#include "constraints/obstacle_rows.hpp"

namespace clik {

void LinkPairsConfig::check(const pinocchio::Model&, const SceneConfig* scene) const {
  if (scene == nullptr) throw std::invalid_argument("LinkPairsConfig: link pairs need a scene");
}

LinkPairs::LinkPairs(const LinkPairsConfig& config, const KindSetup& setup)
    : cfg_(config), model_(setup.model), slot_(setup.slot),
      reach_(config.threshold + setup.monitor_margin) {
  if (setup.scene != nullptr) {
    scene_ = &setup.scene->config();
    n_self_ = static_cast<int>(scene_->self_pairs.size());
  }
  close_.reserve(n_self_);
  pd_.resize(n_self_);
  penetrations_.reserve(n_self_);
  const int nv = setup.model.nv;
  J6a_ = pinocchio::Data::Matrix6x::Zero(6, nv);
  J6b_ = pinocchio::Data::Matrix6x::Zero(6, nv);
  Jp_ = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, nv);
}

// self:<label a>:<label b>
void LinkPairs::names(std::vector<std::string>& out) {
  base_ = static_cast<int>(out.size());
  for (int s = 0; s < n_self_; ++s) {
    const auto& p = scene_->self_pairs[s];
    out.push_back("self:" + scene_->link_labels[p.a] + ":" + scene_->link_labels[p.b]);
  }
}

// LinkPairsRun.evaluate: pairs whose bounding spheres are near, with coal.
void LinkPairs::evaluate(Sample& s, std::vector<Candidate>& out) {
  if (n_self_ == 0) return;
  const SceneConfig& sc = *scene_;
  const auto& pos = s.scene.unplaced().place_joints(s.data);
  const Vec& r = sc.joint_radius;
  close_.clear();
  for (int idx = 0; idx < n_self_; ++idx) {
    const int a = sc.link_slot[sc.self_pairs[idx].a], b = sc.link_slot[sc.self_pairs[idx].b];
    const double dx = pos(a, 0) - pos(b, 0), dy = pos(a, 1) - pos(b, 1), dz = pos(a, 2) - pos(b, 2);
    const double gap = std::sqrt(dx * dx + dy * dy + dz * dz) - r[a] - r[b];
    if (gap < reach_) close_.push_back(idx);
  }
  penetrations_.clear();
  const double thr = cfg_.threshold;
  for (int idx : close_) {
    PairDistance& pd = pd_[idx];
    s.scene.placed().distance(sc.self_pairs[idx].pair, pd);
    const int key = base_ + idx;
    if (pd.distance < 0.0) penetrations_.emplace_back(key, pd.distance);
    if (pd.distance < thr || s.is_active[key]) {
      Candidate c;
      c.key = key;
      c.slot = slot_;
      c.item = idx;
      c.error = thr - pd.distance;
      c.scale = c.threshold = thr;
      c.has_witness = true;
      c.point_a = pd.point_a;
      c.point_b = pd.point_b;
      out.push_back(c);
    }
  }
}

// LinkPairsRun.row: the obstacle row, normalised, with the second link's Jacobian.
void LinkPairs::row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row) {
  static const Vec3 still = Vec3::Zero();
  const PairDistance& pd = pd_[c.item];
  const auto& sp = scene_->self_pairs[c.item];
  point_jacobian(model_, s.data, scene_->link_joint[sp.a], c.point_a, J6a_);
  Jp_ = J6a_.topRows<3>();
  point_jacobian(model_, s.data, scene_->link_joint[sp.b], c.point_b, J6b_);
  Jp_ -= J6b_.topRows<3>();
  const RowTerms rt = obstacle_row(ObstacleForm::normalized, c.threshold, pd.distance, c.point_a,
                                   c.point_b, pd.normal, Jp_, still, row);
  c.error = rt.error;
  c.feed = rt.feed;
}

void LinkPairs::observe_limits(double tk, ViolationMonitor& monitor,
                               const std::vector<std::string>& names) const {
  for (const auto& [key, distance] : penetrations_) {
    monitor.observe_penetration(tk, names[key], distance);
  }
}

void LinkPairsConfig::bind(nanobind::module_& m) {
  bind_threshold_config<LinkPairsConfig>(m, "LinkPairsConfig",
                                         "Link-link rows (self-collision): threshold d_o [m].");
}

}  // namespace clik
