// The speed step (S1)-(S3): see loop/speed_step.hpp and clik/loop/speed_step.py.
#include "loop/speed_step.hpp"

#include <algorithm>
#include <cmath>

namespace clik {

SpeedStep::SpeedStep(const SpeedBounds& bounds, double dt, int nv)
    : v_(bounds.velocity), prev_(Vec::Zero(nv)), c_(Vec::Zero(nv)), u_(Vec::Zero(nv)),
      t_(Vec::Zero(nv)), accel_(bounds.acceleration.size() > 0) {
  if (accel_) a_dt_ = bounds.acceleration * dt;
}

bool SpeedStep::within(const Eigen::Ref<const Vec>& qdot) const {
  for (Eigen::Index i = 0; i < qdot.size(); ++i) {
    if (!(std::abs(qdot[i]) <= v_[i])) return false;
    if (accel_ && !(std::abs(qdot[i] - prev_[i]) <= a_dt_[i])) return false;
  }
  return true;
}

// (S1): min(1, min_i v_i / |c_i|).
double SpeedStep::box_scale(const Vec& c) const {
  double s = 1.0;
  bool any = false;
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    const double a = std::abs(c[i]);
    if (a > v_[i]) {
      const double r = v_[i] / a;
      s = any ? std::min(s, r) : r;
      any = true;
    }
  }
  return s;
}

// (S2): the largest sigma in [0, 1] with |u_i + sigma t_i| <= v_i for every i.
double SpeedStep::fit(const Vec& u, const Vec& t) const {
  double s = 1.0;
  bool any = false;
  const double negligible = NEGLIGIBLE * (t.size() ? t.cwiseAbs().maxCoeff() : 0.0);
  for (Eigen::Index i = 0; i < t.size(); ++i) {
    if (!(std::abs(t[i]) > negligible)) continue;
    const double room = t[i] > 0.0 ? v_[i] - u[i] : v_[i] + u[i];
    const double step = std::abs(t[i]);
    if (step > room) {
      const double r = room / step;
      s = any ? std::min(s, r) : r;
      any = true;
    }
  }
  return std::max(s, 0.0);
}

// (S3): min(1, min_i a_i dt / |change_i|).
double SpeedStep::accel_scale(const Vec& change) const {
  double s = 1.0;
  bool any = false;
  for (Eigen::Index i = 0; i < change.size(); ++i) {
    const double a = std::abs(change[i]);
    if (a > a_dt_[i]) {
      const double r = a_dt_[i] / a;
      s = any ? std::min(s, r) : r;
      any = true;
    }
  }
  return s;
}

void SpeedStep::apply(const ExtendedTask& ext, int r, const Vec* qdot_c, Eigen::Ref<Vec> qdot) {
  if (!qdot.allFinite()) return;  // the divergence check stops it: nothing to bound
  if (within(qdot)) {
    prev_ = qdot;
    return;
  }
  const int m = ext.m;
  if (qdot_c != nullptr) {
    c_ = *qdot_c;
  } else if (r > m) {  // laws (9), (8): the constraint rows' share of (23)
    u_.head(r - m) = ext.K.segment(m, r - m).cwiseProduct(ext.e.segment(m, r - m));
    c_.noalias() = ext.J.middleRows(m, r - m).transpose() * u_.head(r - m);
  } else {
    c_.setZero();
  }
  t_ = qdot - c_;
  u_ = box_scale(c_) * c_;  // (S1)
  qdot = u_ + fit(u_, t_) * t_;  // (S2)
  if (accel_) {  // (S3)
    t_ = qdot - prev_;
    qdot = prev_ + accel_scale(t_) * t_;
  }
  qdot = qdot.cwiseMax(-v_).cwiseMin(v_);  // rounding: a joint at its bound, not 1 ulp past
  prev_ = qdot;
}

void SpeedStep::apply_levels(const Mat& parts, Eigen::Ref<Vec> qdot) {
  if (!qdot.allFinite()) return;
  if (within(qdot)) {
    prev_ = qdot;
    return;
  }
  c_ = parts.row(0).transpose();
  u_ = box_scale(c_) * c_;  // (S1)
  for (Eigen::Index l = 1; l < parts.rows(); ++l) {  // (S2), level by level
    t_ = parts.row(l).transpose();
    u_ += fit(u_, t_) * t_;
  }
  qdot = u_;
  if (accel_) {  // (S3)
    t_ = qdot - prev_;
    qdot = prev_ + accel_scale(t_) * t_;
  }
  qdot = qdot.cwiseMax(-v_).cwiseMin(v_);
  prev_ = qdot;
}

}  // namespace clik
