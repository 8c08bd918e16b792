// A controller's measured joints: see loop/measured.hpp (specification:
// clik/control/measured.py).
#include "loop/measured.hpp"

#include <algorithm>
#include <cmath>

#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/multibody/model.hpp>

namespace clik {

void Measured::restart(const Eigen::Ref<const Vec>& q0) {
  q_.resize(q0.size());
  qdot_.resize(bound_.size());
  d_.resize(bound_.size());
  dq_.resize(bound_.size());
  accepted_ = q0;
  k_accepted_ = 0;
}

namespace {

// The norm summed in order, as numpy sums a short array (Eigen's may pair the terms).
double norm_of(const Vec& q, const Rotation& r) {
  double sum = 0.0;
  for (long i = r.start; i < r.start + r.size; ++i) sum += q[i] * q[i];
  return std::sqrt(sum);
}

}  // namespace

bool Measured::unit_rotations(double tolerance, long& bad) {
  for (std::size_t s = 0; s < rotations_.size(); ++s) {
    if (!(std::abs(norm_of(q_, rotations_[s]) - 1.0) <= tolerance)) {
      bad = static_cast<long>(s);
      return false;
    }
  }
  for (const Rotation& r : rotations_) {
    const double norm = norm_of(q_, r);
    for (long i = r.start; i < r.start + r.size; ++i) q_[i] /= norm;
  }
  return true;
}

bool Measured::jumped(const pinocchio::Model& model, long k, Jump& out) {
  pinocchio::difference(model, accepted_, q_, d_);  // (M3): q_m (-) q_a
  const long n = std::max(k - k_accepted_, 1L);
  long worst = -1;
  double worst_ratio = 0.0;
  for (Eigen::Index i = 0; i < d_.size(); ++i) {
    const double limit = bound_[i] * static_cast<double>(n);
    if (!std::isfinite(limit)) continue;
    const double ratio = std::abs(d_[i]) / limit;
    if (ratio > worst_ratio) {  // the first of the largest, as numpy's argmax
      worst_ratio = ratio;
      worst = static_cast<long>(i);
    }
  }
  if (worst >= 0 && worst_ratio > 1.0) {
    out = Jump{worst, std::abs(d_[worst]), bound_[worst] * static_cast<double>(n),
               k_accepted_, n};
    return true;
  }
  accepted_ = q_;
  k_accepted_ = k;
  return false;
}

void Measured::integrate(const pinocchio::Model& model, const Vec& q, const Vec& qdot,
                         Vec& out) {
  dq_ = qdot * dt_;  // as TrackingRun::step: the same operations, the same bits
  pinocchio::integrate(model, q, dq_, out);
}

}  // namespace clik
