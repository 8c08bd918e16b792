// Link pairs (clik's addition): the obstacle row with a second link in the obstacle's
// place; a kind (see kind.hpp; mirrors clik/constraints/link_pairs.py).
//
// For two links of the robot (the scene's self pairs: not adjacent, not touching at the
// reference configuration), d is their signed distance and d_o the threshold: error
// e = d_o - d, row n^T (J_pa - J_pb) (the normalised form of (13)-(15) with both witness
// points moving), no feed-forward. Pairs are pruned by bounding spheres about the joints
// before coal is asked; the kind's item is the pair's index among the scene's self pairs.
// The limit guarded is contact (a signed distance below zero). Its rows count for the
// bound on active rows but do not ask for one (wants_rows is false, as before).
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "constraints/collision_scene.hpp"
#include "constraints/kind.hpp"
#include "types.hpp"

namespace clik {

class LinkPairs;

struct LinkPairsConfig {
  using Run = LinkPairs;
  double threshold = 0.01;     // d_o of every pair [m]
  std::optional<double> gain;  // [1/s]; none: the law's default

  bool wants_rows() const { return false; }
  void check(const pinocchio::Model& model, const SceneConfig* scene) const;  // a scene
  static void bind(nanobind::module_& m);
};

class LinkPairs : public KindDefaults {
 public:
  LinkPairs(const LinkPairsConfig& config, const KindSetup& setup);
  void names(std::vector<std::string>& out);
  void evaluate(Sample& s, std::vector<Candidate>& out);
  void row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row);
  const std::optional<double>& gain() const { return cfg_.gain; }
  void observe_limits(double tk, ViolationMonitor& monitor,
                      const std::vector<std::string>& names) const;

 private:
  LinkPairsConfig cfg_;
  const pinocchio::Model& model_;
  const SceneConfig* scene_ = nullptr;
  int slot_, base_ = 0, n_self_ = 0;
  double reach_;                   // threshold + monitor margin [m]: the prune's distance
  std::vector<int> close_;         // pairs whose bounding spheres are near
  std::vector<PairDistance> pd_;   // per pair: its last evaluation
  std::vector<std::pair<int, double>> penetrations_;  // (key, distance < 0) this sample
  pinocchio::Data::Matrix6x J6a_, J6b_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> Jp_;
};

}  // namespace clik
