// What a run needs from a ConstraintSet (mirrors clik/constraints/constraint_set.py):
// obstacles and their collision scene, joint ranges, the dexterity row, thresholds,
// gains, the release rule, the bound on active rows. Filled from the Python ConstraintSet
// by `_engine.ConstraintConfig.from_set(cset)` (bind_constraints.cpp); build one
// per run (from_set reads the set as it is then: a later set_obstacles or
// move_obstacle on the Python set is not seen by an existing config).
#pragma once

#include <algorithm>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "constraints/collision_scene.hpp"
#include "constraints/dexterity.hpp"
#include "constraints/joint_limits.hpp"
#include "constraints/obstacle.hpp"
#include "constraints/obstacle_rows.hpp"
#include "types.hpp"

namespace clik {

// "projection" (clik's default) or "sign" (the paper's).
enum class ReleaseRule { projection, sign };

struct ConstraintConfig {
  int nq = 0, nv = 0;                     // the robot's (cset.robot.model)
  std::vector<ObstacleConfig> obstacles;  // always monitored
  bool obstacle_rows = true;              // obstacle rows may enter the task
  ObstacleForm form = ObstacleForm::normalized;
  std::optional<double> obstacle_gain, joint_gain, self_gain;  // [1/s]; none: the law's default
  std::optional<JointLimits> joint_limits;
  std::optional<DexterityConfig> dexterity;   // the dexterity row (D1)-(D3)
  std::optional<double> dexterity_gain;       // [1/s]; none: the law's default
  double self_threshold = 0.01;  // [m]
  ReleaseRule release = ReleaseRule::projection;
  double hysteresis = 0.0;       // sign rule: release when e < -hysteresis * scale
  std::optional<int> max_active; // none: the law's bound
  double monitor_margin = 0.1;   // [m]

  // The scene, when there are obstacles or self-collision (ConstraintSet.scene).
  std::optional<SceneConfig> scene;
  std::vector<std::string> link_labels;  // per link geometry (cset.link_labels)
  Mat rho;                               // (n_links, nv): motion_bounds(model, *scene)

  // Keeps the Python objects behind the borrowed pointers (the GeometryModel) alive.
  std::shared_ptr<void> owner;

  int n_obstacles() const { return static_cast<int>(obstacles.size()); }
  int n_links() const { return scene ? scene->n_links : 0; }
  int n_self() const { return scene ? static_cast<int>(scene->self_pairs.size()) : 0; }

  // Constraint names: obstacle:<obstacle>:<link label>, self:<label a>:<label b>.
  std::string pair_name(int link, int obstacle) const {
    return "obstacle:" + obstacles[obstacle].name + ":" + link_labels[link];
  }
  std::string self_name(int idx) const {
    const auto& p = scene->self_pairs[idx];
    return "self:" + link_labels[p.a] + ":" + link_labels[p.b];
  }

  // The bound on active rows for a task of m rows under `law` (ConstraintSet.row_limit):
  // n - m for laws (9) and (8) (22), n for law (10), lowered by max_active. Throws
  // std::invalid_argument when no row can be active but rows are wanted.
  int row_limit(int m, LawKind law) const {
    const int free = law == LawKind::pseudoinverse ? nv : nv - m;
    const int limit = max_active ? std::min(*max_active, free) : free;
    const bool rows_wanted = obstacle_rows || joint_limits.has_value() || dexterity.has_value();
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
