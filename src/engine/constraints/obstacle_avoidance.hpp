// Obstacle avoidance, eqs. (13)-(15): one row per link-obstacle pair inside its
// threshold; a kind (see kind.hpp; mirrors clik/constraints/obstacle_avoidance.py).
//
// Every link geometry of the shared collision scene is paired with every obstacle; the
// pair (i, o) is the kind's item i * n_obs + o. Distances are monitored through
// certificates: each pair keeps a lower bound of its distance, exact when coal last
// evaluated it, lowered each sample by how far the link can have moved (rho |dq|,
// motion_bounds) and the obstacle's |v| dt. coal is asked only for pairs whose bound is
// below the threshold (or active) and, per obstacle, for the nearest pair within
// threshold + monitor_margin (every obstacle's nearest pair on a recorded sample). The
// limit guarded is the obstacle's surface (a signed distance below zero). Records: each
// obstacle's nearest distance and link per recorded sample, and its run minimum.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "constraints/collision_scene.hpp"
#include "constraints/kind.hpp"
#include "constraints/obstacle.hpp"
#include "constraints/obstacle_rows.hpp"
#include "types.hpp"

namespace clik {

class ObstacleRows;

struct ObstacleRowsConfig {
  using Run = ObstacleRows;
  std::vector<ObstacleConfig> obstacles;  // always monitored
  bool rows = true;                       // their rows may enter the task (false: monitor only)
  ObstacleForm form = ObstacleForm::normalized;
  std::optional<double> gain;             // [1/s]; none: the law's default

  int n_obstacles() const { return static_cast<int>(obstacles.size()); }
  bool wants_rows() const { return rows; }
  // Obstacles need the scene's link geometry, their pairs and geometries in it.
  void check(const pinocchio::Model& model, const SceneConfig* scene) const;
  static void bind(nanobind::module_& m);  // ObstacleConfig and ObstacleRowsConfig
};

class ObstacleRows : public KindDefaults {
 public:
  ObstacleRows(const ObstacleRowsConfig& config, const KindSetup& setup);
  void names(std::vector<std::string>& out);
  void evaluate(Sample& s, std::vector<Candidate>& out);
  void row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row);
  const std::optional<double>& gain() const { return cfg_.gain; }
  // ObstacleRun.move_obstacle: obstacle `name` at `position` at time tk [s], moving with
  // `velocity` from then on; its certificates are dropped (evaluated again).
  bool move_obstacle(const std::string& name, const Vec3& position, const Vec3& velocity,
                     const Mat3& rotation, double tk);
  void observe_limits(double tk, ViolationMonitor& monitor,
                      const std::vector<std::string>& names) const;
  void record(int j);
  double min_distance() const { return min_distance_; }
  void records(std::vector<RecordArray>& out) const;

 private:
  void evaluate_pair(ScenePlacement& scene, int i, int o, Candidate& c);
  void nearest_per_obstacle(Sample& s);

  ObstacleRowsConfig cfg_;
  const pinocchio::Model& model_;
  const SceneConfig* scene_ = nullptr;
  CollisionScene* collision_ = nullptr;  // the run's scene (a moved obstacle's placement)
  double dt_ = 0.0;                      // the run's sample time [s]
  int slot_, base_ = 0, n_obs_, n_links_;
  double min_distance_ = INF;  // this sample's exact nearest distance (inf: none exact)

  // certificates
  Mat rho_;              // (n_links, nv) motion bounds
  Eigen::MatrixXd lb_;   // (n_links, n_obs) distance lower bounds, -inf at the start
                         // (column-major: an obstacle's column is contiguous)
  std::vector<char> evaluated_;  // (n_links * n_obs), row-major
  Vec rho_dq_, obs_step_, thr_o_, margin_o_;
  bool has_obs_step_ = false;
  std::vector<char> moved_;  // per obstacle: moved since the last sample (a controller's)
  std::vector<std::pair<int, int>> todo_;
  std::vector<PairDistance> pd_;  // per pair: its last evaluation
  pinocchio::Data::Matrix6x J6_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> Jp_;

  // per obstacle, this sample
  Vec dist_o_;                 // nearest link distance (a lower bound unless exact_o_)
  std::vector<char> exact_o_;
  Eigen::VectorXi link_o_;     // link geometry of dist_o_, -1 before the first

  // records
  Mat rec_dist_;  // (n_rec, n_obs), inf where unset
  Eigen::Matrix<std::int16_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rec_link_;
  Vec run_min_, run_min_t_;                // (n_obs) inf: never exact
  std::vector<std::int32_t> run_min_link_;  // -1: none
};

}  // namespace clik
