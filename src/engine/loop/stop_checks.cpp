// Stop checks: see loop/stop_checks.hpp and clik/loop/stop_checks.py (the specification).
#include "loop/stop_checks.hpp"

#include <algorithm>
#include <cmath>

namespace clik {

namespace {
// Python's round(): half to even (the default floating-point rounding mode).
long round_half_even(double x) { return static_cast<long>(std::nearbyint(x)); }
}  // namespace

StopChecks::StopChecks(const StopSettings& settings, LawKind law, double dt, int rows)
    : s_(settings), law_(law), dt_(dt),
      window_(std::max(1L, round_half_even(settings.deadlock_window / dt))),
      stall_steps_(std::max(1L, round_half_even(settings.stall_window / dt))),
      S_(rows, 1), A_(rows, rows), Ke_(rows), force_(1), eig_(rows) {}

Stop StopChecks::divergence(const Vec& qdot, double err) {
  jump = qdot.size() ? qdot.cwiseAbs().maxCoeff() * dt_ : 0.0;
  if (!(std::isfinite(err) && std::isfinite(jump))) return Stop::non_finite;
  if (jump > s_.max_joint_step) return Stop::joint_step;
  return Stop::none;
}

double StopChecks::stability_margin(const ExtendedTask& ext, int r) {
  // dt lambda_max(K^1/2 J J^T K^1/2)
  S_.resize(r, ext.nv);
  for (int i = 0; i < r; ++i) S_.row(i) = std::sqrt(ext.K[i]) * ext.J.row(i);
  A_.resize(r, r);
  A_.noalias() = S_ * S_.transpose();
  // Not finite (J J^T overflows): no bound holds, as clik/loop/gains.py says (no eigensolver
  // call on inf, and the same number in both engines).
  if (!A_.allFinite()) return INF;
  eig_.compute(A_, Eigen::EigenvaluesOnly);
  return dt_ * eig_.eigenvalues()[r - 1];
}

Stop StopChecks::instability(long k, const ExtendedTask& ext, int r, double err) {
  if (law_ == LawKind::pseudoinverse) {
    margin = ext.K.head(r).maxCoeff() * dt_;
  } else if (k % STABILITY_EVERY == 0) {
    double bound = 0.0;  // dt trace(K J J^T) >= dt lambda_max
    for (int i = 0; i < r; ++i) bound += ext.K[i] * ext.J.row(i).squaredNorm();
    bound *= dt_;
    margin = bound >= 2.0 ? stability_margin(ext, r) : bound;
  }
  worst_margin = std::max(worst_margin, margin);
  if (margin < 2.0 || err <= s_.deadlock_error) return Stop::none;
  return Stop::unstable;
}

bool StopChecks::deadlock(const ExtendedTask& ext, int r, double err, double blocked) {
  if (law_ == LawKind::pseudoinverse) {
    stuck_ = blocked > BLOCKED_FRACTION ? stuck_ + 1 : 0;
    return stuck_ >= window_ && err > s_.deadlock_error;
  }
  if (err <= s_.deadlock_error) {
    stuck_ = 0;
    return false;
  }
  const auto J = ext.J.topRows(r);
  Ke_.head(r) = ext.K.head(r).cwiseProduct(ext.e.head(r));
  double force2 = 0.0;  // |J^T K e|^2, column by column: no temporary
  for (int c = 0; c < ext.nv; ++c) {
    const double f = J.col(c).dot(Ke_.head(r));
    force2 += f * f;
  }
  const double scale = J.norm() * Ke_.head(r).norm();
  const bool stuck_now = scale > 0.0 && std::sqrt(force2) <= s_.deadlock_ratio * scale;
  stuck_ = stuck_now ? stuck_ + 1 : 0;
  return stuck_ >= window_;
}

bool StopChecks::stall(long k, double err, bool at_rest) {
  if (!(err > s_.deadlock_error && at_rest)) {
    stall_k_ = -1;
    return false;
  }
  if (stall_k_ < 0) {
    stall_k_ = k;
    stall_err_ = err;
    return false;
  }
  if (k - stall_k_ < stall_steps_) return false;
  const bool stalled = err > (1.0 - s_.stall_progress) * stall_err_;
  stall_k_ = k;
  stall_err_ = err;
  return stalled;
}

}  // namespace clik
