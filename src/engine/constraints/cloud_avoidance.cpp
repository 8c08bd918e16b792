// Point-cloud obstacles (C1)-(C2), (13)-(15): see cloud_avoidance.hpp and
// clik/constraints/cloud_avoidance.py (CloudRun: each method names its counterpart).
#include "constraints/cloud_avoidance.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "boundary.hpp"
#include "constraints/cloud_build.hpp"
#include "constraints/obstacle_rows.hpp"

namespace clik {

void CloudRowsConfig::check(const pinocchio::Model&, const SceneConfig* scene) const {
  if (clouds.empty()) return;
  if (scene == nullptr || scene->n_links == 0) {
    throw std::invalid_argument("CloudRowsConfig: clouds without link geometry to check");
  }
}

CloudRows::CloudRows(const CloudRowsConfig& config, const KindSetup& setup)
    : cfg_(config), model_(setup.model), slot_(setup.slot),
      n_c_(static_cast<int>(config.clouds.size())) {
  const int nv = setup.model.nv;
  if (setup.scene != nullptr && n_c_ > 0) {
    scene_ = &setup.scene->config();
    n_links_ = scene_->n_links;
  }
  rho_ = scene_ != nullptr ? motion_bounds(setup.model, *scene_) : Mat::Zero(0, nv);
  for (int i = 0; i < n_links_; ++i) {  // clouds.nearest.local_box
    coal::CollisionGeometry& shape = *scene_->gmodel->geometryObjects[i].geometry;
    shape.computeLocalAABB();
    boxes_.push_back({shape.aabb_local.min_, shape.aabb_local.max_});
  }
  int most = 0;
  reach_ = Vec::Zero(n_c_);
  for (int c = 0; c < n_c_; ++c) {
    most = std::max(most, cfg_.clouds[c].size());
    reach_[c] = cfg_.clouds[c].threshold + cfg_.search_margin;
  }
  query_.reserve(most);
  const auto n_pairs = static_cast<std::size_t>(n_links_) * n_c_;
  lb_ = Eigen::MatrixXd::Constant(n_links_, n_c_, -INF);
  evaluated_.assign(n_pairs, 0);
  found_.assign(n_pairs, 0);
  replaced_.assign(n_c_, 0);
  rho_dq_ = Vec::Zero(n_links_);
  nearest_.resize(n_pairs);
  J6_ = pinocchio::Data::Matrix6x::Zero(6, nv);
  Jp_ = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, nv);
  dist_c_ = Vec::Constant(n_c_, INF);
  exact_c_.assign(n_c_, 0);
  link_c_ = Eigen::VectorXi::Constant(n_c_, -1);
  rec_dist_ = Mat::Constant(setup.n_rec, n_c_, INF);
  rec_link_.setConstant(setup.n_rec, n_c_, -1);
  run_min_ = Vec::Constant(n_c_, INF);
  run_min_t_ = Vec::Zero(n_c_);
  run_min_link_.assign(n_c_, -1);
}

// cloud:<cloud>:<link label>, pair (i, c) at i * n_clouds + c.
void CloudRows::names(std::vector<std::string>& out) {
  base_ = static_cast<int>(out.size());
  for (int i = 0; i < n_links_; ++i) {
    for (const CloudConfig& cloud : cfg_.clouds) {
      out.push_back("cloud:" + cloud.name + ":" + scene_->link_labels[i]);
    }
  }
}

// CloudRun.evaluate: pairs through certificates, then each cloud's nearest pair.
void CloudRows::evaluate(Sample& s, std::vector<Candidate>& out) {
  if (n_c_ == 0 || n_links_ == 0) return;
  if (s.dq_abs != nullptr) {
    rho_dq_.noalias() = rho_ * *s.dq_abs;
    lb_.colwise() -= rho_dq_;
  }
  std::fill(evaluated_.begin(), evaluated_.end(), 0);
  Candidate cand;
  const auto visit = [&](int i, int c) {
    char& done = evaluated_[static_cast<std::size_t>(i) * n_c_ + c];
    if (done) return;
    done = 1;
    if (!evaluate_pair(s, i, c, cand)) return;  // nothing within reach (an active one released)
    const bool held = s.is_active[cand.key] && !replaced_[static_cast<std::size_t>(c)];
    if (cfg_.rows && (lb_(i, c) < cand.threshold || held)) out.push_back(cand);
  };
  for (int i = 0; i < n_links_; ++i) {  // row-major, as np.argwhere
    for (int c = 0; c < n_c_; ++c) {
      if (lb_(i, c) < cfg_.clouds[c].threshold) visit(i, c);
    }
  }
  for (const Candidate& a : s.active) {
    if (a.slot == slot_) visit(a.item / n_c_, a.item % n_c_);
  }
  double nearest = INF;
  for (int c = 0; c < n_c_; ++c) {  // each cloud's nearest link, exact within reach
    Eigen::Index i;
    while (true) {
      lb_.col(c).minCoeff(&i);
      const auto pair = static_cast<std::size_t>(i) * n_c_ + c;
      if (evaluated_[pair] || !(lb_(i, c) < reach_[c])) break;
      evaluate_pair(s, static_cast<int>(i), c, cand);
      evaluated_[pair] = 1;
    }
    const auto pair = static_cast<std::size_t>(i) * n_c_ + c;
    dist_c_[c] = lb_(i, c);
    exact_c_[c] = evaluated_[pair] && found_[pair];
    link_c_[c] = static_cast<int>(i);
    const double d = exact_c_[c] ? dist_c_[c] : INF;
    nearest = std::min(nearest, d);
    if (d < run_min_[c]) {
      run_min_[c] = d;
      run_min_t_[c] = s.tk;
      run_min_link_[c] = link_c_[c];
    }
  }
  std::fill(replaced_.begin(), replaced_.end(), 0);
  min_distance_ = nearest;
}

// CloudRun._evaluate: link geometry i against cloud c within reach; its certificate.
bool CloudRows::evaluate_pair(Sample& s, int i, int c, Candidate& out) {
  const auto pair = static_cast<std::size_t>(i) * n_c_ + c;
  const pinocchio::SE3& placement = s.scene.placed().placement(i);
  const coal::CollisionGeometry& shape = *scene_->gmodel->geometryObjects[i].geometry;
  NearestSphere& found = nearest_[pair];
  const int hint = found.sphere;  // the last evaluation's sphere (-1: none)
  const bool near =
      query_.nearest(cfg_.clouds[c], shape, boxes_[i], placement, reach_[c], hint, found);
  found_[pair] = near;
  if (!near) {
    lb_(i, c) = reach_[c];
    found.sphere = -1;
    return false;
  }
  lb_(i, c) = found.distance;
  const double thr = cfg_.clouds[c].threshold;
  const int item = i * n_c_ + c;
  out.key = base_ + item;
  out.slot = slot_;
  out.item = item;
  out.error = thr - found.distance;
  out.scale = thr;
  out.threshold = thr;
  out.feed = 0.0;
  out.has_witness = true;
  out.point_a = found.on_link;
  out.point_b = found.on_cloud;
  return true;
}

// CloudRun.row: (15), normalised, from the nearest sphere's witness pair.
void CloudRows::row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row) {
  const NearestSphere& found = nearest_[static_cast<std::size_t>(c.item)];
  const int i = c.item / n_c_;
  point_jacobian(model_, s.data, scene_->link_joint[i], found.on_link, J6_);
  Jp_ = J6_.topRows<3>();
  const RowTerms rt = obstacle_row(ObstacleForm::normalized, c.threshold, found.distance,
                                   found.on_link, found.on_cloud, found.normal, Jp_,
                                   Vec3::Zero(), row);
  c.error = rt.error;
  c.feed = rt.feed;
}

bool CloudRows::replace_cloud(const CloudConfig& cloud) {
  for (int c = 0; c < n_c_; ++c) {
    if (cfg_.clouds[c].name != cloud.name) continue;
    cfg_.clouds[c] = cloud;
    query_.reserve(cloud.size());
    reach_[c] = cloud.threshold + cfg_.search_margin;
    lb_.col(c).setConstant(-INF);
    for (int i = 0; i < n_links_; ++i) nearest_[static_cast<std::size_t>(i) * n_c_ + c] = {};
    replaced_[static_cast<std::size_t>(c)] = 1;
    return true;
  }
  return false;
}

void CloudRows::observe_limits(double tk, ViolationMonitor& monitor,
                               const std::vector<std::string>& names) const {
  if (!(min_distance_ < 0.0)) return;
  for (int c = 0; c < n_c_; ++c) {
    if (dist_c_[c] < 0.0) {
      monitor.observe_penetration(tk, names[base_ + link_c_[c] * n_c_ + c], dist_c_[c]);
    }
  }
}

void CloudRows::record(int j) {
  if (n_c_ == 0) return;
  rec_dist_.row(j) = dist_c_.transpose();
  rec_link_.row(j) = link_c_.transpose().cast<std::int16_t>();
}

void CloudRows::records(std::vector<RecordArray>& out) const {
  if (n_c_ == 0) return;
  using T = RecordArray::Type;
  const auto n_c = static_cast<std::size_t>(n_c_);
  const auto n_rec = static_cast<std::size_t>(rec_dist_.rows());
  out.push_back({"cloud_distance", T::f64, rec_dist_.data(), {n_rec, n_c}, true, false});
  out.push_back({"cloud_link", T::i16, rec_link_.data(), {n_rec, n_c}, true, false});
  out.push_back({"run_min", T::f64, run_min_.data(), {n_c}, false, false});
  out.push_back({"run_min_link", T::i32, run_min_link_.data(), {n_c}, false, true});
  out.push_back({"run_min_t", T::f64, run_min_t_.data(), {n_c}, false, false});
}

// -- Python: the typed configs -------------------------------------------------------------

void CloudRowsConfig::bind(nanobind::module_& m) {
  namespace nb = nanobind;
  using Centres = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  m.attr("CLOUD_GJK_TOLERANCE") = CLOUD_GJK_TOLERANCE;
  m.attr("POINT_RADIUS") = POINT_RADIUS;
  m.attr("MAX_PLANES") = MAX_PLANES;
  m.attr("MAX_GRID_SPAN") = MAX_GRID_SPAN;
  m.attr("MIN_CELL") = MIN_CELL;
  nb::class_<CloudConfig>(m, "CloudConfig", "A cloud's voxel spheres in their grid.")
      .def(
          "__init__",
          [](CloudConfig* self, std::string name, const Centres& centres, const Vec& radii,
             double cell, const Vec3& low, const Eigen::Vector3i& dims,
             const Eigen::VectorXi& order, const Eigen::VectorXi& start, double threshold) {
            CloudConfig cloud{std::move(name), centres, radii, cell, low, dims, order, start,
                              threshold};
            cloud.check();
            new (self) CloudConfig(std::move(cloud));
          },
          nb::kw_only(), nb::arg("name"), nb::arg("centres"), nb::arg("radii"), nb::arg("cell"),
          nb::arg("low"), nb::arg("dims"), nb::arg("order"), nb::arg("start"),
          nb::arg("threshold"),
          "clik.clouds.grid.SphereGrid's arrays: centres (K, 3), radii (K) [m], cell [m], "
          "low (3) [m], dims (3), order (K), start (cells + 1); threshold d_o [m].")
      .def_static(
          "build",
          [](const std::string& name,
             const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>&
                 points,
             double voxel, const Mat3& rotation, const Vec3& position, double threshold) {
            int dropped = 0;
            CloudConfig cloud = build_cloud(name, points, voxel, rotation, position, threshold,
                                            dropped);
            return std::make_pair(std::move(cloud), dropped);
          },
          nb::arg("name"), nb::arg("points"), nb::arg("voxel"), nb::arg("rotation"),
          nb::arg("position"), nb::arg("threshold"),
          "(CloudConfig, dropped): the voxel spheres and grid of points (N, 3) [m] in the "
          "cloud's frame, as clik.clouds builds them (NaN or infinite rows dropped).")
      .def_ro("name", &CloudConfig::name)
      .def_ro("threshold", &CloudConfig::threshold)
      .def_ro("centres", &CloudConfig::centres)
      .def_ro("radii", &CloudConfig::radii)
      .def_ro("cell", &CloudConfig::cell)
      .def_ro("low", &CloudConfig::low)
      .def_ro("dims", &CloudConfig::dims)
      .def_ro("order", &CloudConfig::order)
      .def_ro("start", &CloudConfig::start)
      .def_prop_ro("size", &CloudConfig::size);

  nb::class_<CloudRowsConfig>(m, "CloudRowsConfig",
                              "Link-cloud rows (C1)-(C2), (13)-(15) and the clouds' monitoring.")
      .def(
          "__init__",
          [](CloudRowsConfig* self, std::vector<CloudConfig> clouds, bool rows,
             double search_margin, std::optional<double> gain) {
            require_gain(gain, "CloudRowsConfig");
            require(std::isfinite(search_margin) && search_margin >= 0.0,
                    "CloudRowsConfig: search_margin a finite distance >= 0 [m]");
            new (self) CloudRowsConfig{std::move(clouds), rows, search_margin, gain};
          },
          nb::kw_only(), nb::arg("clouds"), nb::arg("rows"), nb::arg("search_margin"),
          nb::arg("gain").none() = nb::none())
      .def_ro("clouds", &CloudRowsConfig::clouds)
      .def_ro("rows", &CloudRowsConfig::rows)
      .def_ro("search_margin", &CloudRowsConfig::search_margin)
      .def_ro("gain", &CloudRowsConfig::gain);
}

}  // namespace clik
