// The kinds of constraint rows, in one place (mirrors clik/constraints/registry.py).
//
// A kind is a config type and a run type (see kind.hpp); adding one is its header and
// source, and its place in the list below. Nothing else names a kind: the core
// (ConstraintRun) and the bindings visit these variants. The order is the order of the
// kinds' keys, and of their evaluation, within a set: the set's config lists its kinds in
// this order.
#pragma once

#include <variant>

#include "constraints/cloud_avoidance.hpp"
#include "constraints/cone.hpp"
#include "constraints/dexterity.hpp"
#include "constraints/joint_limits.hpp"
#include "constraints/link_pairs.hpp"
#include "constraints/obstacle_avoidance.hpp"
#include "constraints/workspace.hpp"

namespace clik {

using KindConfig = std::variant<JointRangeConfig, ObstacleRowsConfig, LinkPairsConfig,
                                DexterityConfig, WorkspaceConfig, ConeConfig, CloudRowsConfig>;

namespace detail {
template <typename Configs>
struct Kinds;
template <typename... Config>
struct Kinds<std::variant<Config...>> {
  using Run = std::variant<typename Config::Run...>;
  template <typename F>
  static void each(F&& f) {
    (f(static_cast<Config*>(nullptr)), ...);
  }
};
}  // namespace detail

// Each kind's run, alternative for alternative.
using KindRun = detail::Kinds<KindConfig>::Run;

// f(static_cast<Config*>(nullptr)) for each kind's config type, in order (bindings).
template <typename F>
void for_each_kind_config(F&& f) {
  detail::Kinds<KindConfig>::each(f);
}

}  // namespace clik
