// What a run needs from a ConstraintSet (mirrors clik/constraints/constraint_set.py): the
// kinds' typed configs in the set's order, the shared collision scene, the release rule
// and the bound on active rows. Built from Python as `_engine.ConstraintSetConfig(...)`
// (clik/constraints/engine_config.py; bound in bind_constraints.cpp), validated there
// against the robot's model and the scene. One config serves any number of runs: each
// ConstraintRun copies it and keeps its own state.
#pragma once

#include <algorithm>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <pinocchio/multibody/model.hpp>

#include "boundary.hpp"
#include "constraints/collision_scene.hpp"
#include "constraints/kinds.hpp"
#include "types.hpp"

namespace clik {

// "projection" (clik's default) or "sign" (the paper's).
enum class ReleaseRule { projection, sign };

struct ConstraintSetConfig {
  const pinocchio::Model* model = nullptr;  // the robot's (borrowed)
  std::shared_ptr<void> owner;              // keeps the pin.Model behind `model` alive
  std::vector<KindConfig> kinds;            // in the set's order (kinds.hpp)
  std::optional<SceneConfig> scene;         // link geometry and obstacles, shared by the kinds
  ReleaseRule release = ReleaseRule::projection;
  double hysteresis = 0.0;        // sign rule: release when e < -hysteresis * scale
  std::optional<int> max_active;  // none: the law's bound
  double monitor_margin = 0.1;    // [m]
  ModelShape built;               // the model's sizes when validated

  // Each kind checked against the robot and the scene; std::invalid_argument.
  void validate() const {
    if (model == nullptr) throw std::invalid_argument("ConstraintSetConfig: no model");
    if (!finite_nonnegative(hysteresis) || !finite_positive(monitor_margin) ||
        (max_active && *max_active < 0)) {
      throw std::invalid_argument(
          "ConstraintSetConfig: hysteresis finite >= 0, monitor_margin finite > 0 [m], "
          "max_active >= 0");
    }
    if (scene) scene->check(*model);
    const SceneConfig* sc = scene ? &*scene : nullptr;
    for (const KindConfig& kind : kinds) {
      std::visit([&](const auto& k) { k.check(*model, sc); }, kind);
    }
  }

  // Throws unless the model and the scene's GeometryModel are still as validated.
  void require_unchanged() const {
    require_same_model(built, *model, "ConstraintSetConfig");
    if (scene) scene->require_unchanged();
  }

  // The bound on active rows for a task of m rows under `law` (ConstraintSet.row_limit):
  // n - m for laws (9) and (8) (22), n for law (10), lowered by max_active. Throws
  // std::invalid_argument when no row can be active but a kind wants rows.
  int row_limit(int m, LawKind law) const {
    const int nv = model->nv;
    const int free = law == LawKind::pseudoinverse ? nv : nv - m;
    const int limit = max_active ? std::min(*max_active, free) : free;
    bool rows_wanted = false;
    for (const KindConfig& kind : kinds) {
      rows_wanted = rows_wanted || std::visit([](const auto& k) { return k.wants_rows(); }, kind);
    }
    if (limit <= 0 && rows_wanted) {
      throw std::invalid_argument(
          "constraints: constraint rows need a redundant task (n - m > 0) under laws (9) and "
          "(8): n = " + std::to_string(nv) + ", m = " + std::to_string(m) +
          "; use law 'pseudoinverse' (constraints first) or a smaller task mask");
    }
    return limit;
  }
};

}  // namespace clik
