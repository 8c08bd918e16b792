// A run's goals, the core every kind shares: see tasks/goals.hpp and tasks/goal_kind.hpp.
#include "tasks/goals.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace clik {

void check_rows(const std::vector<int>& rows, int n, const std::string& who) {
  if (rows.empty() || static_cast<int>(rows.size()) > n) {
    throw std::invalid_argument(who + ": rows, 1 to " + std::to_string(n) + " rows among 0.." +
                                std::to_string(n - 1));
  }
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i] < 0 || rows[i] >= n) {
      throw std::invalid_argument(who + ": rows, each among 0.." + std::to_string(n - 1));
    }
    for (size_t j = 0; j < i; ++j) {
      if (rows[j] == rows[i]) throw std::invalid_argument(who + ": rows, each row once");
    }
  }
}

void check_frame(const pinocchio::Model& model, int frame, const std::string& who) {
  if (frame < 0 || frame >= static_cast<int>(model.nframes)) {
    throw std::invalid_argument(who + ", a frame index of the model");
  }
}

double wrap_angle(double x) {
  constexpr double pi = 3.14159265358979323846, two_pi = 2.0 * pi;
  double r = std::fmod(x + pi, two_pi);  // np.remainder(x + pi, 2 pi) - pi, as in Python
  if (r < 0.0) r += two_pi;
  return r - pi;
}

void frame_columns(const pinocchio::Model& model, int frame, int& lo, int& hi) {
  const auto joint = model.frames[static_cast<size_t>(frame)].parentJoint;
  for (const auto j : model.supports[joint]) {
    if (j == 0) continue;  // the universe
    const auto& jm = model.joints[j];
    if (jm.shortname().find("Mimic") != std::string::npos) {
      lo = 0;
      hi = model.nv;
      return;
    }
    lo = std::min(lo, jm.idx_v());
    hi = std::max(hi, jm.idx_v() + jm.nv());
  }
}

Goals::Goals(const pinocchio::Model& model, const std::vector<GoalConfig>& goals) {
  runs_.reserve(goals.size());
  for (const GoalConfig& goal : goals) {
    std::visit(
        [&](const auto& config) {
          using Run = typename std::decay_t<decltype(config)>::Run;
          runs_.emplace_back(std::in_place_type<Run>, model, config);
        },
        goal);
    std::visit(
        [&](const auto& run) {
          ref_at_.push_back(ref_size_);
          ff_at_.push_back(ff_size_);
          rows_ += run.rows();
          ref_size_ += run.ref_size();
          ff_size_ += run.ff_size();
          run.frames(frames_);
          com_ = com_ || run.needs_com();
        },
        runs_.back());
    row_end_.push_back(rows_);
  }
}

TargetReader Goals::target(int g) const {
  return std::visit([](const auto& run) { return run.target(); }, runs_[g]);
}

void Goals::write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
                  int m0) {
  for (int g = 0; g < count(); ++g) {
    const int start = g ? row_end_[g - 1] : 0;
    std::visit([&](auto& run) { run.write(c, ref + ref_at_[g], ff + ff_at_[g], ext, m0 + start); },
               runs_[g]);
  }
}

void Goals::norms(const ExtendedTask& ext, int m0, Mat& out) const {
  for (int g = 0; g < count(); ++g) {
    const int start = g ? row_end_[g - 1] : 0;
    std::visit([&](const auto& run) { run.norms(ext, m0 + start, out(g, 0), out(g, 1)); },
               runs_[g]);
  }
}

void Goals::columns(const pinocchio::Model& model, int* lo, int* hi) const {
  for (int g = 0; g < count(); ++g) {
    const int start = g ? row_end_[g - 1] : 0;
    std::visit([&](const auto& run) { run.columns(model, lo + start, hi + start); }, runs_[g]);
  }
}

}  // namespace clik
