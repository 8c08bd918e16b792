// Obstacle avoidance (13)-(15): see obstacle_avoidance.hpp and
// clik/constraints/obstacle_avoidance.py (ObstacleRun: each method names its counterpart).
#include "constraints/obstacle_avoidance.hpp"

#include "boundary.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

namespace clik {

void ObstacleRowsConfig::check(const pinocchio::Model&, const SceneConfig* scene) const {
  const int n_obs = n_obstacles();
  if (n_obs == 0) return;
  if (scene == nullptr || scene->n_links == 0) {
    throw std::invalid_argument("ObstacleRowsConfig: obstacles without link geometry to check");
  }
  if (scene->n_obstacles() != n_obs) {
    throw std::invalid_argument("ObstacleRowsConfig: " + std::to_string(n_obs) +
                                " obstacles but the scene's obstacle_pairs has " +
                                std::to_string(scene->n_obstacles()) + " columns");
  }
  const auto& pairs = scene->gmodel->collisionPairs;
  for (int o = 0; o < n_obs; ++o) {
    const ObstacleConfig& ob = obstacles[o];
    if (ob.geometry < 0) continue;  // the scene's: its pairs' second geometry
    for (int i = 0; i < scene->n_links; ++i) {
      const auto& pair = pairs[static_cast<std::size_t>(scene->obstacle_pairs(i, o))];
      if (static_cast<int>(pair.second) != ob.geometry &&
          static_cast<int>(pair.first) != ob.geometry) {
        throw std::invalid_argument(
            "ObstacleRowsConfig: obstacle " + ob.name + ": geometry " +
            std::to_string(ob.geometry) + " is not in its collision pairs (the scene's "
            "obstacle_geom index of the obstacle is expected)");
      }
    }
  }
}

ObstacleRows::ObstacleRows(const ObstacleRowsConfig& config, const KindSetup& setup)
    : cfg_(config), model_(setup.model), slot_(setup.slot), n_obs_(config.n_obstacles()) {
  const int nv = setup.model.nv;
  if (setup.scene != nullptr && n_obs_ > 0) {
    scene_ = &setup.scene->config();
    collision_ = setup.scene;
    for (int o = 0; o < n_obs_; ++o) {
      ObstacleConfig& ob = cfg_.obstacles[o];
      if (ob.geometry < 0) {  // the scene's: (link geometry, obstacle geometry) pairs
        const auto pair = static_cast<std::size_t>(scene_->obstacle_pairs(0, o));
        ob.geometry = static_cast<int>(scene_->gmodel->collisionPairs[pair].second);
      }
      setup.scene->move_with(ob);
    }
  }
  n_links_ = scene_ != nullptr ? scene_->n_links : 0;
  rho_ = scene_ != nullptr ? motion_bounds(setup.model, *scene_) : Mat::Zero(0, nv);
  lb_ = Eigen::MatrixXd::Constant(n_links_, n_obs_, -INF);
  evaluated_.assign(static_cast<std::size_t>(n_links_) * n_obs_, 0);
  rho_dq_ = Vec::Zero(n_links_);
  thr_o_ = Vec::Zero(n_obs_);
  margin_o_ = Vec::Zero(n_obs_);
  obs_step_ = Vec::Zero(n_obs_);
  const double dt = setup.dt();
  dt_ = dt;
  for (int o = 0; o < n_obs_; ++o) {
    const ObstacleConfig& ob = cfg_.obstacles[o];
    thr_o_[o] = ob.threshold;
    margin_o_[o] = ob.threshold + setup.monitor_margin;
    const Vec3& v = ob.velocity;
    obs_step_[o] = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt;
    has_obs_step_ = has_obs_step_ || obs_step_[o] > 0.0;
  }
  const int n_pairs = n_links_ * n_obs_;
  todo_.reserve(2 * static_cast<std::size_t>(n_pairs));  // near pairs, then the active
  pd_.resize(static_cast<std::size_t>(n_pairs));
  J6_ = pinocchio::Data::Matrix6x::Zero(6, nv);
  Jp_ = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, nv);
  dist_o_ = Vec::Constant(n_obs_, INF);
  exact_o_.assign(n_obs_, 0);
  link_o_ = Eigen::VectorXi::Constant(n_obs_, -1);
  rec_dist_ = Mat::Constant(setup.n_rec, n_obs_, INF);
  rec_link_.setConstant(setup.n_rec, n_obs_, -1);
  run_min_ = Vec::Constant(n_obs_, INF);
  run_min_t_ = Vec::Zero(n_obs_);
  run_min_link_.assign(n_obs_, -1);
  moved_.assign(n_obs_, 0);
}

bool ObstacleRows::move_obstacle(const std::string& name, const Vec3& position,
                                 const Vec3& velocity, const Mat3& rotation, double tk) {
  for (int o = 0; o < n_obs_; ++o) {
    ObstacleConfig& ob = cfg_.obstacles[o];
    if (ob.name != name) continue;
    ob.position = position - tk * velocity;  // the pose at t = 0 of the same motion
    ob.velocity = velocity;
    ob.rotation = rotation;
    const Vec3& v = velocity;
    obs_step_[o] = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt_;
    has_obs_step_ = (obs_step_.array() > 0.0).any();
    lb_.col(o).setConstant(-INF);  // its distances are unknown: evaluated again
    moved_[static_cast<std::size_t>(o)] = 1;
    if (collision_ != nullptr) collision_->set_obstacle(ob);
    return true;
  }
  return false;
}

// obstacle:<obstacle>:<link label>, pair (i, o) at i * n_obs + o.
void ObstacleRows::names(std::vector<std::string>& out) {
  base_ = static_cast<int>(out.size());
  for (int i = 0; i < n_links_; ++i) {
    for (const ObstacleConfig& ob : cfg_.obstacles) {
      out.push_back("obstacle:" + ob.name + ":" + scene_->link_labels[i]);
    }
  }
}

// ObstacleRun.evaluate: link-obstacle pairs through distance certificates.
void ObstacleRows::evaluate(Sample& s, std::vector<Candidate>& out) {
  if (n_obs_ == 0) return;
  if (s.dq_abs != nullptr) {
    rho_dq_.noalias() = rho_ * *s.dq_abs;
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
  for (const Candidate& c : s.active) {
    if (c.slot == slot_) todo_.emplace_back(c.item / n_obs_, c.item % n_obs_);
  }
  Candidate c;
  for (const auto& [i, o] : todo_) {  // the pairs near their threshold, and the active
    char& done = evaluated_[static_cast<std::size_t>(i) * n_obs_ + o];
    if (done) continue;
    evaluate_pair(s.scene, i, o, c);
    const double distance = pd_[c.item].distance;
    lb_(i, o) = distance;
    done = 1;
    // an active pair stays a candidate, unless its obstacle was just moved and it is
    // beyond its threshold: then it is released (a jump must not pull the link after it)
    const bool held = s.is_active[c.key] && !moved_[static_cast<std::size_t>(o)];
    if (cfg_.rows && (distance < c.threshold || held)) out.push_back(c);
  }
  nearest_per_obstacle(s);
  std::fill(moved_.begin(), moved_.end(), 0);  // a move counts for one sample
}

// Then each obstacle's nearest link (the first smallest bound, as np.argmin), until it is
// exact or beyond the margin. A pair evaluated here is at or beyond its threshold (its
// bound was), so it is never a candidate.
void ObstacleRows::nearest_per_obstacle(Sample& s) {
  Candidate c;
  for (int o = 0; o < n_obs_; ++o) {
    const double margin = s.exact ? INF : margin_o_[o];
    while (true) {
      Eigen::Index best;
      dist_o_[o] = lb_.col(o).minCoeff(&best);
      link_o_[o] = static_cast<int>(best);
      char& known = evaluated_[static_cast<std::size_t>(best) * n_obs_ + o];
      exact_o_[o] = known;
      if (known || !(dist_o_[o] < margin)) break;
      evaluate_pair(s.scene, static_cast<int>(best), o, c);
      lb_(best, o) = pd_[c.item].distance;
      known = 1;
    }
  }
  double nearest = INF;
  for (int o = 0; o < n_obs_; ++o) {
    const double d = exact_o_[o] ? dist_o_[o] : INF;
    nearest = std::min(nearest, d);
    if (d < run_min_[o]) {
      run_min_[o] = d;
      run_min_t_[o] = s.tk;
      run_min_link_[o] = link_o_[o];
    }
  }
  min_distance_ = nearest;
}

// ObstacleRun._pair: distance, witness points and error of link geometry i and obstacle o.
void ObstacleRows::evaluate_pair(ScenePlacement& scene, int i, int o, Candidate& c) {
  const int item = i * n_obs_ + o;
  PairDistance& pd = pd_[static_cast<std::size_t>(item)];
  scene.placed().distance(scene_->obstacle_pairs(i, o), pd);
  const double thr = thr_o_[o];
  const ErrorScale es = obstacle_error(cfg_.form, thr, pd.distance);
  c.key = base_ + item;
  c.slot = slot_;
  c.item = item;
  c.error = es.error;
  c.scale = es.scale;
  c.threshold = thr;
  c.feed = 0.0;
  c.has_witness = true;
  c.point_a = pd.point_a;
  c.point_b = pd.point_b;
}

// ObstacleRun.row: (13)-(15) from the pair's witness points.
void ObstacleRows::row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row) {
  const PairDistance& pd = pd_[static_cast<std::size_t>(c.item)];
  const int i = c.item / n_obs_, o = c.item % n_obs_;
  point_jacobian(model_, s.data, scene_->link_joint[i], c.point_a, J6_);
  Jp_ = J6_.topRows<3>();
  const RowTerms rt = obstacle_row(cfg_.form, c.threshold, pd.distance, c.point_a, c.point_b,
                                   pd.normal, Jp_, cfg_.obstacles[o].velocity, row);
  c.error = rt.error;
  c.feed = rt.feed;
}

void ObstacleRows::observe_limits(double tk, ViolationMonitor& monitor,
                                  const std::vector<std::string>& names) const {
  if (!(min_distance_ < 0.0)) return;  // a penetrating pair is always evaluated: exact
  for (int o = 0; o < n_obs_; ++o) {
    if (dist_o_[o] < 0.0) {
      monitor.observe_penetration(tk, names[base_ + link_o_[o] * n_obs_ + o], dist_o_[o]);
    }
  }
}

void ObstacleRows::record(int j) {
  if (n_obs_ == 0) return;
  rec_dist_.row(j) = dist_o_.transpose();
  rec_link_.row(j) = link_o_.transpose().cast<std::int16_t>();
}

void ObstacleRows::records(std::vector<RecordArray>& out) const {
  if (n_obs_ == 0) return;
  using T = RecordArray::Type;
  const auto n_obs = static_cast<std::size_t>(n_obs_);
  const auto n_rec = static_cast<std::size_t>(rec_dist_.rows());
  out.push_back({"obstacle_distance", T::f64, rec_dist_.data(), {n_rec, n_obs}, true, false});
  out.push_back({"obstacle_link", T::i16, rec_link_.data(), {n_rec, n_obs}, true, false});
  out.push_back({"run_min", T::f64, run_min_.data(), {n_obs}, false, false});
  out.push_back({"run_min_link", T::i32, run_min_link_.data(), {n_obs}, false, true});
  out.push_back({"run_min_t", T::f64, run_min_t_.data(), {n_obs}, false, false});
}

// -- Python: the typed configs -------------------------------------------------------------

void ObstacleRowsConfig::bind(nanobind::module_& m) {
  namespace nb = nanobind;
  nb::class_<ObstacleConfig>(m, "ObstacleConfig", "An obstacle as a run sees it.")
      .def(
          "__init__",
          [](ObstacleConfig* self, std::string name, const Vec3& position, const Mat3& rotation,
             const Vec3& velocity, double threshold, int geometry) {
            if (!(std::isfinite(threshold) && threshold > 0.0)) {
              throw std::invalid_argument("ObstacleConfig " + name + ": a positive threshold [m]");
            }
            require(position.allFinite() && rotation.allFinite() && velocity.allFinite(),
                    "ObstacleConfig " + name + ": finite position [m], rotation and velocity [m/s]");
            new (self) ObstacleConfig{std::move(name), rotation, position, velocity, threshold,
                                      geometry};
          },
          nb::kw_only(), nb::arg("name"), nb::arg("position"), nb::arg("rotation"),
          nb::arg("velocity"), nb::arg("threshold"), nb::arg("geometry") = -1,
          "position, velocity [m, m/s] at t = 0; rotation (3, 3); threshold d_o [m]; geometry: "
          "its index in the scene's GeometryModel (CollisionScene.obstacle_geom); -1: the one "
          "its collision pairs name.")
      .def_ro("name", &ObstacleConfig::name)
      .def_ro("position", &ObstacleConfig::position)
      .def_ro("rotation", &ObstacleConfig::rotation)
      .def_ro("velocity", &ObstacleConfig::velocity)
      .def_ro("threshold", &ObstacleConfig::threshold)
      .def_ro("geometry", &ObstacleConfig::geometry);

  nb::class_<ObstacleRowsConfig>(m, "ObstacleRowsConfig",
                                 "Link-obstacle rows (13)-(15) and the obstacles' monitoring.")
      .def(
          "__init__",
          [](ObstacleRowsConfig* self, std::vector<ObstacleConfig> obstacles, bool rows,
             const std::string& form, std::optional<double> gain) {
            require_gain(gain, "ObstacleRowsConfig");
            if (form != "normalized" && form != "squared") {
              throw std::invalid_argument(
                  "ObstacleRowsConfig: form 'normalized' or 'squared', got '" + form + "'");
            }
            new (self) ObstacleRowsConfig{
                std::move(obstacles), rows,
                form == "squared" ? ObstacleForm::squared : ObstacleForm::normalized, gain};
          },
          nb::kw_only(), nb::arg("obstacles"), nb::arg("rows"), nb::arg("form"),
          nb::arg("gain").none() = nb::none())
      .def_ro("obstacles", &ObstacleRowsConfig::obstacles)
      .def_ro("rows", &ObstacleRowsConfig::rows)
      .def_prop_ro("form",
                   [](const ObstacleRowsConfig& c) {
                     return c.form == ObstacleForm::squared ? "squared" : "normalized";
                   })
      .def_ro("gain", &ObstacleRowsConfig::gain);
}

}  // namespace clik
