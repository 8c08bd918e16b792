// The null-space objectives of eq. (5), qdot += N z (mirrors clik/objectives and
// clik/loop/levels.py): each objective's z [rad/s] at one sample, the gradient of a
// criterion times its gain, acting in the null space of the constraints and of the
// levels 1 .. level. Law (10) only. Allocated once per run.
//
//   joint_centering: z[idx_v] = -gain (q[idx_q] - center) / half_range^2
//   posture:         z = gain * difference(model, q, q_ref)
//   manipulability:  z = gain * grad w, w = sqrt(det(J0 J0^T)) of the primary task's rows
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "constraints/dexterity.hpp"
#include "types.hpp"

namespace clik {

enum class ObjectiveKind { joint_centering, posture, manipulability };

// `_engine.ObjectiveConfig`.
struct ObjectiveConfig {
  ObjectiveKind kind = ObjectiveKind::posture;
  double gain = 0.0;  // [1/s]
  int level = 1;      // acts below levels 1 .. level
  std::vector<int> idx_q, idx_v;  // joint_centering: the joints with finite limits
  Vec center, half_range;         // joint_centering [rad or m]
  Vec q_ref;                      // posture (nq)
};

ObjectiveKind objective_kind(const std::string& kind);

class Objectives {
 public:
  // Throws std::invalid_argument naming the field when a config does not fit the model,
  // the levels (1 .. n_levels) or the primary task (frame, rows).
  Objectives(const pinocchio::Model& model, const std::vector<ObjectiveConfig>& configs,
             int n_levels, int frame, const std::vector<int>& task_rows);

  int count() const { return static_cast<int>(cfg_.size()); }
  bool empty() const { return cfg_.empty(); }
  int level(int i) const { return cfg_[i].level; }

  // Each objective's z at q into z[i] (nv). data: joint Jacobians at q; J0: the primary
  // task's rows of the extended task.
  void compute(const pinocchio::Model& model, pinocchio::Data& data, const Vec& q,
               const Eigen::Ref<const Mat>& J0, std::vector<Vec>& z);

 private:
  std::vector<ObjectiveConfig> cfg_;
  std::unique_ptr<DexterityRow> dex_;  // manipulability's gradient
  Eigen::RowVectorXd grad_;
};

}  // namespace clik
