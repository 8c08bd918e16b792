// Point-cloud obstacles, (C1)-(C2) with the obstacle rows (13)-(15): one row per
// link-cloud pair within its threshold; a kind (see kind.hpp; mirrors
// clik/constraints/cloud_avoidance.py, each method naming its counterpart).
//
// Pair (link geometry i, cloud c) is the kind's item i * n_clouds + c. Each pair keeps a
// certificate: a lower bound of its distance, lowered each sample by rho_i |dq|. The grid
// is searched (CloudQuery) only for pairs whose bound is below the threshold, or active,
// up to reach = d_o + search_margin: a pair with no sphere within reach gets the bound
// reach. Then each cloud's nearest pair is evaluated until it is exact or beyond reach.
// A cloud is at rest between updates (replace_cloud): no feed-forward. The limit guarded
// is the spheres' surface (a signed distance below zero).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "constraints/cloud_query.hpp"
#include "constraints/collision_scene.hpp"
#include "constraints/kind.hpp"
#include "types.hpp"

namespace clik {

class CloudRows;

struct CloudRowsConfig {
  using Run = CloudRows;
  std::vector<CloudConfig> clouds;  // always monitored
  bool rows = true;                 // their rows may enter the task (false: monitor only)
  double search_margin = 0.02;      // reach = d_o + search_margin [m]
  std::optional<double> gain;       // [1/s]; none: the law's default

  bool wants_rows() const { return rows && !clouds.empty(); }
  // Clouds need the scene's link geometry.
  void check(const pinocchio::Model& model, const SceneConfig* scene) const;
  static void bind(nanobind::module_& m);  // CloudConfig and CloudRowsConfig
};

class CloudRows : public KindDefaults {
 public:
  CloudRows(const CloudRowsConfig& config, const KindSetup& setup);
  void names(std::vector<std::string>& out);
  void evaluate(Sample& s, std::vector<Candidate>& out);
  void row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row);
  const std::optional<double>& gain() const { return cfg_.gain; }
  // CloudRun.replace_cloud: the cloud so named, new spheres (checked); its certificates
  // dropped. False: no cloud so named.
  bool replace_cloud(const CloudConfig& cloud);
  void observe_limits(double tk, ViolationMonitor& monitor,
                      const std::vector<std::string>& names) const;
  void record(int j);
  double min_distance() const { return min_distance_; }
  void records(std::vector<RecordArray>& out) const;

 private:
  bool evaluate_pair(Sample& s, int i, int c, Candidate& out);

  CloudRowsConfig cfg_;
  const pinocchio::Model& model_;
  const SceneConfig* scene_ = nullptr;
  int slot_, base_ = 0, n_c_, n_links_ = 0;
  double min_distance_ = INF;

  std::vector<LocalBox> boxes_;  // per link geometry
  CloudQuery query_;
  Mat rho_;                      // (n_links, nv) motion bounds
  Eigen::MatrixXd lb_;           // (n_links, n_clouds) certificates, -inf at the start
  std::vector<char> evaluated_, found_;  // (n_links * n_clouds), row-major
  std::vector<char> replaced_;   // per cloud: replaced since the last sample
  Vec rho_dq_, reach_;
  std::vector<NearestSphere> nearest_;  // per pair: its last evaluation
  pinocchio::Data::Matrix6x J6_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> Jp_;

  Vec dist_c_;                  // per cloud, this sample: nearest link distance [m]
  std::vector<char> exact_c_;
  Eigen::VectorXi link_c_;

  Mat rec_dist_;
  Eigen::Matrix<std::int16_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rec_link_;
  Vec run_min_, run_min_t_;
  std::vector<std::int32_t> run_min_link_;
};

}  // namespace clik
