// Limits crossed during a run (mirrors clik/constraints/violations.py): a joint past its
// limit (the tighter of the robot's and a joint-range constraint's), a link
// inside an obstacle or another link, a frame beyond a wall or outside a cone. Strings are made only when a limit is
// first crossed.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "types.hpp"

namespace clik {

constexpr double JOINT_TOLERANCE = 1e-9;  // excursion not counted (rounding) [rad or m]

struct ViolationRecord {
  std::string constraint;
  std::string kind;  // "joint", "obstacle" (a penetration), "length" or "angle"
  double t_first, t_last, worst;
};

// The joint limits to stay in (clik.constraints.violations.JointRange): configuration
// indices, bounds and joint names (`_engine.JointMonitorConfig`).
struct JointMonitorConfig {
  std::vector<int> index;
  Vec lower, upper;
  std::vector<std::string> names;
};

class ViolationMonitor {
 public:
  explicit ViolationMonitor(JointMonitorConfig joints) : j_(std::move(joints)) {}

  void observe_joints(double t, const Vec& q) {
    const std::size_t n = j_.index.size();
    for (std::size_t s = 0; s < n; ++s) {  // lower limits first, as clik/constraints/violations.py
      const double qi = q[j_.index[s]];
      if (qi < j_.lower[s] - JOINT_TOLERANCE) {
        note("joint:" + j_.names[s] + ":lower", "joint", t, j_.lower[s] - qi);
      }
    }
    for (std::size_t s = 0; s < n; ++s) {
      const double qi = q[j_.index[s]];
      if (qi > j_.upper[s] + JOINT_TOLERANCE) {
        note("joint:" + j_.names[s] + ":upper", "joint", t, qi - j_.upper[s]);
      }
    }
  }

  // A signed distance below zero [m] (an obstacle or a link pair).
  void observe_penetration(double t, const std::string& key, double distance) {
    note(key, "obstacle", t, -distance);
  }

  // A limit crossed by excess > 0: kind "length" [m] or "angle" [rad] (a workspace
  // wall, a cone's surface).
  void observe_excursion(double t, const std::string& key, const char* kind, double excess) {
    note(key, kind, t, excess);
  }

  // In the order the limits were first crossed (as recorded).
  const std::vector<ViolationRecord>& records() const { return records_; }

  // Every limit crossing noted so far (one per limit per sample): a caller compares it
  // before and after a sample to tell whether that sample crossed any.
  long notes() const { return notes_; }

 private:
  void note(const std::string& key, const char* kind, double t, double excess) {
    ++notes_;
    auto it = where_.find(key);
    if (it == where_.end()) {
      where_.emplace(key, records_.size());
      records_.push_back({key, kind, t, t, excess});
      return;
    }
    ViolationRecord& rec = records_[it->second];
    rec.t_last = t;
    rec.worst = std::max(rec.worst, excess);
  }

  JointMonitorConfig j_;
  std::vector<ViolationRecord> records_;
  std::unordered_map<std::string, std::size_t> where_;
  long notes_ = 0;
};

}  // namespace clik
