// The extra goals: see tasks/goals.hpp and clik/loop/tracking.py (the specification).
#include "tasks/goals.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/spatial/explog.hpp>
#include <pinocchio/spatial/skew.hpp>

namespace clik {

namespace {

constexpr auto LWA = pinocchio::LOCAL_WORLD_ALIGNED;
using RowMat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

void fail(const std::string& what) { throw std::invalid_argument(what); }

// rows: distinct, increasing? no: any order, each in [0, n).
void check_rows(const std::vector<int>& rows, int n, const std::string& who) {
  if (rows.empty() || static_cast<int>(rows.size()) > n) {
    fail(who + ": rows, 1 to " + std::to_string(n) + " rows among 0.." + std::to_string(n - 1));
  }
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i] < 0 || rows[i] >= n) {
      fail(who + ": rows, each among 0.." + std::to_string(n - 1));
    }
    for (size_t j = 0; j < i; ++j) {
      if (rows[j] == rows[i]) fail(who + ": rows, each row once");
    }
  }
}

}  // namespace

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

// -- FrameGoal -----------------------------------------------------------------------

FrameGoalRun::FrameGoalRun(const pinocchio::Model& model, const FrameGoal& goal)
    : frame_(goal.frame), relative_to_(goal.relative_to), rows_(goal.rows),
      Ja_(6, model.nv), Jb_(6, model.nv), e6_(Eigen::Matrix<double, 6, 1>::Zero()) {
  const int nf = static_cast<int>(model.nframes);
  if (goal.frame < 0 || goal.frame >= nf) fail("FrameGoal: frame, a frame index of the model");
  if (goal.relative_to < -1 || goal.relative_to >= nf || goal.relative_to == goal.frame) {
    fail("FrameGoal: relative_to, -1 (the world) or another frame index of the model");
  }
  check_rows(goal.rows, 6, "FrameGoal");
  Ja_.setZero();
  Jb_.setZero();
}

void FrameGoalRun::write(const GoalContext& c, const double* ref, const double* ff,
                         ExtendedTask& ext, int row0) {
  const auto fa = static_cast<pinocchio::FrameIndex>(frame_);
  const pinocchio::SE3& oMa = c.data.oMf[fa];
  const Eigen::Map<const Vec3> p_d(ref);
  const Eigen::Map<const RowMat3> R_d(ref + 3);
  // getFrameJacobian writes the frame's support columns, the same at every sample: the
  // others stay zero unless the relative form below wrote them
  if (relative_to_ >= 0) Ja_.setZero();
  pinocchio::getFrameJacobian(c.model, c.data, fa, LWA, Ja_);
  const Eigen::Matrix<double, 6, Eigen::Dynamic>* J = &Ja_;
  if (relative_to_ < 0) {
    e6_.head<3>() = p_d - oMa.translation();
    e6_.tail<3>() = pinocchio::log3((R_d * oMa.rotation().transpose()).eval());
  } else {
    // bMa = oMb^-1 oMa: p = R_b^T (p_a - p_b), R = R_b^T R_a; its Jacobian in B's axes.
    const auto fb = static_cast<pinocchio::FrameIndex>(relative_to_);
    const pinocchio::SE3& oMb = c.data.oMf[fb];
    const Mat3& Rb = oMb.rotation();
    const Vec3 d = oMa.translation() - oMb.translation();
    const Vec3 p = Rb.transpose() * d;
    const Mat3 R = Rb.transpose() * oMa.rotation();
    e6_.head<3>() = p_d - p;
    e6_.tail<3>() = pinocchio::log3((R_d * R.transpose()).eval());
    Jb_.setZero();
    pinocchio::getFrameJacobian(c.model, c.data, fb, LWA, Jb_);
    // J_lin = R_b^T (J_a_lin - J_b_lin + skew(p_a - p_b) J_b_ang), J_ang = R_b^T (J_a_ang - J_b_ang)
    Ja_.topRows<3>() -= Jb_.topRows<3>();
    Ja_.topRows<3>().noalias() += pinocchio::skew(d) * Jb_.bottomRows<3>();
    Ja_.bottomRows<3>() -= Jb_.bottomRows<3>();
    Jb_.topRows<3>().noalias() = Rb.transpose() * Ja_.topRows<3>();
    Jb_.bottomRows<3>().noalias() = Rb.transpose() * Ja_.bottomRows<3>();
    J = &Jb_;
  }
  for (int i = 0; i < rows(); ++i) {
    const int row = rows_[i];
    ext.e[row0 + i] = e6_[row];
    ext.J.row(row0 + i) = J->row(row);
    ext.ff[row0 + i] = ff[i];
  }
}

void FrameGoalRun::norms(const ExtendedTask& ext, int row0, double& first, double& second) const {
  double p2 = 0.0, r2 = 0.0;
  bool pos = false;
  for (int i = 0; i < rows(); ++i) {
    const double e = ext.e[row0 + i];
    if (rows_[i] < 3) {
      p2 += e * e;
      pos = true;
    } else {
      r2 += e * e;
    }
  }
  second = std::sqrt(r2);
  first = pos ? std::sqrt(p2) : second;
}

void FrameGoalRun::columns(const pinocchio::Model& model, int* lo, int* hi) const {
  int a = model.nv, b = 0;
  frame_columns(model, frame_, a, b);
  if (relative_to_ >= 0) frame_columns(model, relative_to_, a, b);
  if (a >= b) a = model.nv, b = 0;
  std::fill(lo, lo + rows(), a);
  std::fill(hi, hi + rows(), b);
}

// -- PostureGoal ---------------------------------------------------------------------

PostureGoalRun::PostureGoalRun(const pinocchio::Model& model, const PostureGoal& goal)
    : idx_q_(goal.idx_q), idx_v_(goal.idx_v), continuous_(goal.continuous.begin(),
                                                          goal.continuous.end()) {
  const size_t n = idx_q_.size();
  if (n == 0 || idx_v_.size() != n || continuous_.size() != n) {
    fail("PostureGoal: idx_q, idx_v and continuous, one entry per joint (at least one)");
  }
  for (size_t i = 0; i < n; ++i) {
    const int width = continuous_[i] ? 2 : 1;
    if (idx_q_[i] < 0 || idx_q_[i] + width > model.nq) {
      fail("PostureGoal: idx_q, configuration indices of the model (continuous: two)");
    }
    if (idx_v_[i] < 0 || idx_v_[i] >= model.nv) {
      fail("PostureGoal: idx_v, velocity indices of the model");
    }
  }
}

void PostureGoalRun::write(const GoalContext& c, const double* ref, const double* ff,
                           ExtendedTask& ext, int row0) {
  for (int i = 0; i < rows(); ++i) {
    const int iq = idx_q_[i];
    const double e = continuous_[i]
                         ? wrap_angle(ref[i] - std::atan2(c.q[iq + 1], c.q[iq]))
                         : ref[i] - c.q[iq];
    ext.e[row0 + i] = e;
    ext.J(row0 + i, idx_v_[i]) = 1.0;  // the row's other entries: zero from the start
    ext.ff[row0 + i] = ff[i];
  }
}

void PostureGoalRun::norms(const ExtendedTask& ext, int row0, double& first,
                           double& second) const {
  first = ext.e.segment(row0, rows()).norm();
  second = 0.0;
}

void PostureGoalRun::columns(const pinocchio::Model&, int* lo, int* hi) const {
  for (int i = 0; i < rows(); ++i) {
    lo[i] = idx_v_[i];
    hi[i] = idx_v_[i] + 1;
  }
}

// -- ComGoal -------------------------------------------------------------------------

ComGoalRun::ComGoalRun(const pinocchio::Model&, const ComGoal& goal) : rows_(goal.rows) {
  check_rows(goal.rows, 3, "ComGoal");
}

void ComGoalRun::write(const GoalContext& c, const double* ref, const double* ff,
                       ExtendedTask& ext, int row0) {
  const Vec3& com = c.data.com[0];
  for (int i = 0; i < rows(); ++i) {
    const int row = rows_[i];
    ext.e[row0 + i] = ref[row] - com[row];
    ext.J.row(row0 + i) = c.data.Jcom.row(row);
    ext.ff[row0 + i] = ff[i];
  }
}

void ComGoalRun::norms(const ExtendedTask& ext, int row0, double& first, double& second) const {
  first = ext.e.segment(row0, rows()).norm();
  second = 0.0;
}

void ComGoalRun::columns(const pinocchio::Model& model, int* lo, int* hi) const {
  std::fill(lo, lo + rows(), 0);
  std::fill(hi, hi + rows(), model.nv);
}

// -- Goals ---------------------------------------------------------------------------

Goals::Goals(const pinocchio::Model& model, const std::vector<GoalConfig>& goals) {
  runs_.reserve(goals.size());
  for (const GoalConfig& goal : goals) {
    std::visit(
        [&](const auto& g) {
          using G = std::decay_t<decltype(g)>;
          if constexpr (std::is_same_v<G, FrameGoal>) {
            runs_.emplace_back(std::in_place_type<FrameGoalRun>, model, g);
            frames_.push_back(g.frame);
            if (g.relative_to >= 0) frames_.push_back(g.relative_to);
          } else if constexpr (std::is_same_v<G, PostureGoal>) {
            runs_.emplace_back(std::in_place_type<PostureGoalRun>, model, g);
          } else {
            runs_.emplace_back(std::in_place_type<ComGoalRun>, model, g);
            com_ = true;
          }
        },
        goal);
    std::visit(
        [&](const auto& run) {
          rows_ += run.rows();
          ref_at_.push_back(ref_size_);
          ref_size_ += run.ref_size();
        },
        runs_.back());
    row_end_.push_back(rows_);
  }
}

TargetReader FrameGoalRun::target() const {
  const bool pos = std::any_of(rows_.begin(), rows_.end(), [](int r) { return r < 3; });
  const bool rot = std::any_of(rows_.begin(), rows_.end(), [](int r) { return r >= 3; });
  return FrameTarget{pos, rot, rows_, true};
}

TargetReader Goals::target(int g) const {
  return std::visit([](const auto& run) { return run.target(); }, runs_[g]);
}

void Goals::write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
                  int m0) {
  for (int g = 0; g < count(); ++g) {
    const int start = g ? row_end_[g - 1] : 0;
    std::visit([&](auto& run) { run.write(c, ref + ref_at_[g], ff + start, ext, m0 + start); },
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
