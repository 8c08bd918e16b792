// Workspace box (W1)-(W2) of docs/method.md (mirrors clik/constraints/workspace.py):
// a frame's origin p kept inside lower <= p <= upper [m] (world frame). Each of the
// six walls is a row like a joint range: d the distance to the wall (p_a - lower_a,
// or upper_a - p_a), error e = d_w - d (W1), row +J_a (lower wall) or -J_a (upper
// wall), J_a a row of the frame's world-aligned linear Jacobian (W2), no feed-forward.
// Items 0..2: lower x, y, z; 3..5: upper x, y, z. The limit guarded is the wall.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "constraints/kind.hpp"
#include "types.hpp"

namespace clik {

class Workspace;

struct WorkspaceConfig {
  using Run = Workspace;
  int frame = -1;                 // the frame whose origin is kept in the box
  Vec3 lower = Vec3::Zero();      // [m], world frame
  Vec3 upper = Vec3::Zero();      // [m]
  double threshold = 0.0;         // d_w [m]
  std::vector<std::string> keys;  // the six walls' names, in item order
  std::optional<double> gain;     // [1/s]; none: the law's default

  bool wants_rows() const { return true; }
  // Throws std::invalid_argument for a frame the model does not have.
  void check(const pinocchio::Model& model, const SceneConfig*) const;
  static void bind(nanobind::module_& m);
};

class Workspace : public KindDefaults {
 public:
  Workspace(const WorkspaceConfig& config, const KindSetup& setup);
  void names(std::vector<std::string>& out);
  void evaluate(Sample& s, std::vector<Candidate>& out);
  void row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row);
  const std::optional<double>& gain() const { return cfg_.gain; }
  // The origin beyond a wall: its distance below zero, as a length excursion.
  void observe_limits(double tk, ViolationMonitor& monitor,
                      const std::vector<std::string>& names) const;

 private:
  WorkspaceConfig cfg_;
  int slot_, base_ = 0;
  Eigen::Matrix<double, 6, 1> d_ = Eigen::Matrix<double, 6, 1>::Constant(INF);
  pinocchio::Data::Matrix6x J_;
};

}  // namespace clik
