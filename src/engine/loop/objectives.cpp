// The objectives of eq. (5): see loop/objectives.hpp.
#include "loop/objectives.hpp"

#include <cmath>
#include <stdexcept>

#include <pinocchio/algorithm/joint-configuration.hpp>

namespace clik {

ObjectiveKind objective_kind(const std::string& kind) {
  if (kind == "joint_centering") return ObjectiveKind::joint_centering;
  if (kind == "posture") return ObjectiveKind::posture;
  if (kind == "manipulability") return ObjectiveKind::manipulability;
  throw std::invalid_argument(
      "ObjectiveConfig: kind, 'joint_centering', 'posture' or 'manipulability', got '" + kind +
      "'");
}

Objectives::Objectives(const pinocchio::Model& model, const std::vector<ObjectiveConfig>& configs,
                       int n_levels, int frame, const std::vector<int>& task_rows)
    : cfg_(configs), grad_(Eigen::RowVectorXd::Zero(model.nv)) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(what);
  };
  for (const ObjectiveConfig& c : cfg_) {
    require(std::isfinite(c.gain) && c.gain >= 0.0, "ObjectiveConfig: gain, finite >= 0 [1/s]");
    require(c.level >= 1 && c.level <= n_levels,
            "ObjectiveConfig: level, among 1 .. the run's levels (LawConfig.levels)");
    switch (c.kind) {
      case ObjectiveKind::joint_centering: {
        const auto n = static_cast<Eigen::Index>(c.idx_q.size());
        require(static_cast<Eigen::Index>(c.idx_v.size()) == n && c.center.size() == n &&
                    c.half_range.size() == n,
                "ObjectiveConfig: joint_centering needs idx_q, idx_v, center and half_range "
                "of one size");
        for (Eigen::Index i = 0; i < n; ++i) {
          require(c.idx_q[i] >= 0 && c.idx_q[i] < model.nq && c.idx_v[i] >= 0 &&
                      c.idx_v[i] < model.nv,
                  "ObjectiveConfig: idx_q, idx_v, indices of the model's q and v");
          require(std::isfinite(c.center[i]) && std::isfinite(c.half_range[i]) &&
                      c.half_range[i] > 0.0,
                  "ObjectiveConfig: center finite, half_range finite > 0 [rad or m]");
        }
        break;
      }
      case ObjectiveKind::posture:
        require(c.q_ref.size() == model.nq && c.q_ref.allFinite(),
                "ObjectiveConfig: posture needs q_ref, nq finite numbers");
        break;
      case ObjectiveKind::manipulability:
        if (!dex_) dex_ = std::make_unique<DexterityRow>(model, frame, task_rows);
        break;
    }
  }
}

void Objectives::compute(const pinocchio::Model& model, pinocchio::Data& data, const Vec& q,
                         const Eigen::Ref<const Mat>& J0, std::vector<Vec>& z) {
  bool manip_done = false;
  for (int i = 0; i < count(); ++i) {
    const ObjectiveConfig& c = cfg_[i];
    Vec& zi = z[i];
    switch (c.kind) {
      case ObjectiveKind::joint_centering:
        zi.setZero();
        for (size_t j = 0; j < c.idx_q.size(); ++j) {
          const double h = c.half_range[j];
          zi[c.idx_v[j]] = -c.gain * (q[c.idx_q[j]] - c.center[j]) / (h * h);
        }
        break;
      case ObjectiveKind::posture:
        pinocchio::difference(model, q, c.q_ref, zi);
        zi *= c.gain;
        break;
      case ObjectiveKind::manipulability:
        if (!manip_done) {
          dex_->evaluate(J0);
          dex_->gradient(model, data, grad_);
          manip_done = true;
        }
        zi = c.gain * grad_.transpose();
        break;
    }
  }
}

}  // namespace clik
