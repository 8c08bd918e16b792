// Law (10) by priority levels with eq. (5)'s objectives: see loop/laws.hpp and
// clik/loop/levels.py's prioritized_levels (the specification). The same projectors,
// computed in the coordinates of an orthonormal basis Z of the directions still free
// (docs/method.md, "Several tasks", the compiled engine's form): a level of n rows with
// k free directions costs an n x k product and a min(n, k)-sized solve; the regular
// cases by Cholesky factorisations (small_dense.hpp), eigenpairs only in the damping band.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "loop/laws.hpp"
#include "loop/regular_factor.hpp"
#include "loop/small_dense.hpp"

namespace clik {

Law::Level::Level(int n, int nv)
    : M(n, nv), A(n, n), S(n, n), rest(n), y(n), tmp(n), work(2 * std::max(n, nv)), lo(n), hi(n),
      eig(n > MAX_EIGEN_ROWS ? n : 0), eig_small(n <= MAX_EIGEN_ROWS ? n : 0) {}

Law::Law(const LawSettings& settings, int rows, int nv, int m, const LevelPlan& plan)
    : Law(settings, rows, nv) {
  ends_ = plan.ends.empty() ? std::vector<int>{m} : plan.ends;
  zlevel_ = plan.objective_levels;
  by_levels_ = s_.kind == LawKind::pseudoinverse &&
               (ends_.size() > 1 || m > MAX_TASK_ROWS || !zlevel_.empty());
  if (!by_levels_) return;
  const int L = static_cast<int>(ends_.size());
  int start = 0;
  // Built in place, never moved: an Eigen solver not yet computed has no defined info()
  // to copy (UBSan: a load of an invalid ComputationInfo).
  level_.reserve(static_cast<std::size_t>(L));
  for (int l = 0; l < L; ++l) {
    level_.emplace_back(ends_[l] - start, nv);
    level_.back().basis = l + 1 < L;
    start = ends_[l];
  }
  for (int lz : zlevel_) {
    if (lz < 1 || lz > L) throw std::invalid_argument("Law: an objective's level, 1 to L");
    level_[static_cast<size_t>(lz - 1)].basis = true;
  }
  z_.assign(zlevel_.size(), Vec::Zero(nv));
  Z_.setZero(nv, nv);
  Zn_.setZero(nv, nv);
  P_.setZero(nv, nv);
  W_.setZero(nv, nv);
  G_.setZero(nv, nv);
  Gs_.setZero(nv, nv);
  beta_.setZero(nv);
  tk_.setZero(nv);
  parts_.setZero(1 + L, nv);
  out_.setZero(nv);
  zp_.setZero(nv);
  lscale_.setZero(L);
  span_.assign(2 * static_cast<size_t>(nv), 0);
  scan_rows_ = plan.lo.empty();
  if (!scan_rows_ && (plan.lo.size() != static_cast<size_t>(m) || plan.hi.size() != plan.lo.size())) {
    throw std::invalid_argument("Law: plan.lo and plan.hi, one window per task row");
  }
  jlo_ = scan_rows_ ? std::vector<int>(static_cast<size_t>(m), 0) : plan.lo;
  jhi_ = scan_rows_ ? std::vector<int>(static_cast<size_t>(m), nv) : plan.hi;
  unit_plan_ = L == 2 && zlevel_.empty() && !scan_rows_;
  for (int i = ends_[0]; unit_plan_ && i < m; ++i) unit_plan_ = jhi_[i] == jlo_[i] + 1;
  if (!unit_plan_) return;
  const int n1 = ends_[0];
  fpos_.assign(static_cast<size_t>(nv), 0);
  fcols_.assign(static_cast<size_t>(nv), 0);
  epos_.assign(static_cast<size_t>(nv), 0);
  hit_.assign(static_cast<size_t>(nv), 0);
  M1_.setZero(n1, nv);
  A1_.setZero(n1, n1);
  Pe_.setZero(nv + 2, nv + 2);  // L^-1 [M1[:, E], M1 u]: n1 rows of e + 1 (even) values
  H_.setZero(nv, nv);
  Hs_.setZero(nv, 2 * nv);  // the factor, and a scratch factor
  u_.setZero(nv);
  g_.setZero(nv);
  t_.setZero(nv);
  s1_.setZero(std::max(n1, 2 * nv));
}

namespace {

// The largest row norm of n contiguous rows of nv (0 without rows), each row taken over
// [lo[i], hi[i]) where it may not be zero (with scan, found: a NaN or an infinite entry
// is inside); into finite, whether every row's squared norm is finite (false for a NaN
// or an infinite entry, or an entry beyond 1e154 whose square overflows).
double rows_scale(const double* J, int n, int nv, bool scan, bool& finite, int* lo, int* hi) {
  double top = 0.0, zero = 0.0;
  for (int i = 0; i < n; ++i) {
    const double* row = J + i * nv;
    if (scan) small::nonzero_range(row, nv, lo[i], hi[i]);
    const double s = lo[i] < hi[i] ? small::dot(row + lo[i], row + lo[i], hi[i] - lo[i]) : 0.0;
    top = std::max(top, s);
    zero += s * 0.0;  // NaN once a sum is NaN or infinite
  }
  finite = finite && zero == 0.0;
  return std::sqrt(top);
}

}  // namespace

// The constraint level on C = J[m:m+v] (v >= 1): parts_[0] = C^# b_c within the budget;
// Z loses C's right singular vectors above the rank tolerance (relative to level 1's
// scale).
void Law::level_constraints(const ExtendedTask& ext, int v, double scale1) {
  const int m = ext.m;
  const double epsilon = CONDITION_RATIO * scale1;
  const double d2 = s_.damping * s_.damping;
  const double keep = RANK_TOLERANCE * std::max(scale1, 1.0);
  Eigen::Map<Vec> part(parts_.row(0).data(), ext.nv);
  if (v == 1) {
    const auto c = ext.J.row(m);
    const double s = c.norm();
    if (s == 0.0) {
      part.setZero();
      return;
    }
    const double gain = s / (std::max(s * s, epsilon * epsilon) + d2);
    part.noalias() = (gain * b_[m] / s) * c.transpose();
    budget(part, s_.dt);
    if (s > keep) {
      P_.col(0) = c.transpose() / s;
      remove_directions(1);
    }
    return;
  }
  ConstraintBlock& block = constraint_[static_cast<size_t>(v - 1)];
  block.C = ext.J.middleRows(m, v);
  block.svd.compute(block.C, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = block.svd.singularValues();
  const auto& U = block.svd.matrixU();
  const auto& Vm = block.svd.matrixV();
  const Eigen::Index k = sv.size();
  for (Eigen::Index i = 0; i < k; ++i) {
    gain_[i] = sv[i] / (std::max(sv[i] * sv[i], epsilon * epsilon) + d2);
  }
  tmp_.head(k).noalias() = U.transpose() * b_.segment(m, v);
  tmp_.head(k).array() *= gain_.head(k).array();
  part.noalias() = Vm * tmp_.head(k);
  budget(part, s_.dt);
  int p = 0;
  for (Eigen::Index i = 0; i < k; ++i) {
    if (sv[i] > keep) P_.col(p++) = Vm.col(i);
  }
  remove_directions(p);
}

// One level of n rows J_l with the demand lv.rest (b_l - J_l qdot above), in the k_
// free directions: JN = J_l Z Z^T = M Z^T, so JN JN^T = M M^T and
// JN^T f(JN JN^T) = Z f(M^T M) M^T (f: damped_solve's filter, on the nonzero
// eigenvalues). part = Z x with x from the smaller of the two Gram matrices when it is
// regular (every eigenvalue above the filter's floor), from the eigenpairs of M M^T in
// the damping band. A basis level then removes M's row space from Z.
void Law::solve_level(Level& lv, const double* Jl, const int* jlo, const int* jhi, double scale,
                      double* part) {
  const int n = static_cast<int>(lv.rest.size()), k = k_, nv = static_cast<int>(Z_.rows());
  if (k == 0) {  // nothing left to move: JN = 0
    std::fill(part, part + nv, 0.0);
    return;
  }
  Tolerances tol;
  tol.eps2 = std::pow(CONDITION_RATIO * scale, 2);
  tol.d2 = s_.damping * s_.damping;
  const double keep = RANK_TOLERANCE * std::max(scale, 1.0);
  tol.kept = std::max(keep * keep, GRAM_TOLERANCE * scale * scale);
  // a basis level keeps every direction when the floor clears its tolerance too
  tol.floor = lv.basis ? std::max(tol.eps2, tol.kept) : tol.eps2;
  tol.top = scale * scale;  // M M^T's diagonal: |J_l Z row|^2 <= scale^2
  // M = J_l Z, row i at M + i * nv (J_l itself while Z is the identity), its windows
  const double* M = Jl;
  if (z_identity_) {
    std::copy(jlo, jlo + n, lv.lo.begin());
    std::copy(jhi, jhi + n, lv.hi.begin());
  } else {
    small::row_dots(Jl, nv, n, Z_.data(), nv, k, nv, lv.M.data(), nv, false, jlo, jhi);
    M = lv.M.data();
    for (int i = 0; i < n; ++i) small::nonzero_range(M + i * nv, k, lv.lo[i], lv.hi[i]);
  }
  const bool rows = n <= k && solve_rows(lv, M, tol);
  int p = n <= k ? n : k;  // the regular case keeps every direction
  if (!rows && !(n > k && solve_columns(lv, M, tol))) p = solve_eigenpairs(lv, M, tol);
  const double* x = tk_.data();
  if (z_identity_) {  // part = Z x
    std::copy(x, x + k, part);
  } else {
    small::combine_rows(x, Z_.data(), nv, k, part, nv);
  }
  if (!lv.basis) return;
  if (rows) {  // L = chol(M M^T): lv.S's factor when undamped
    if (tol.d2 > 0.0) factor_shifted(lv.A.data(), n, n, 0.0, lv.S.data(), n);
    if (remove_rows(M, n, lv.S.data(), lv.lo.data(), lv.hi.data())) return;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < k; ++j) P_(j, i) = M[i * nv + j];
    }
  }
  remove_directions(p);
}

// x = M^T y (k_) into tk_.
void Law::times_rows(const double* M, int n, const double* y) {
  const int k = k_, nv = static_cast<int>(Z_.rows());
  double* x = tk_.data();
  small::combine_rows(y, M, nv, n, x, k);
}

// n <= k: x = M^T (M M^T + lambda_0^2 I)^-1 rest when M M^T's eigenvalues clear the floor.
// Undamped, by modified Gram-Schmidt on M's rows (orthonormal_rows: M = L Q, L L^T =
// M M^T), x = Q^T L^-1 rest, and Q is ready for remove_rows; damped, from the Cholesky
// factorisation of M M^T + lambda_0^2 I (lv.S keeps the factor).
bool Law::solve_rows(Level& lv, const double* M, const Tolerances& tol) {
  const int n = static_cast<int>(lv.rest.size()), nv = static_cast<int>(Z_.rows());
  q_ready_ = false;
  if (tol.d2 > 0.0) {
    small::gram_rows(M, nv, n, k_, lv.A.data(), n, lv.lo.data(), lv.hi.data());
    if (!factor_regular(lv.A.data(), n, n, tol.floor, tol.d2, lv.S.data(), n, lv.work.data())) {
      return false;
    }
    lv.y = lv.rest;
    small::cholesky_solve(lv.S.data(), n, n, lv.y.data());
    times_rows(M, n, lv.y.data());
    return true;
  }
  if (!orthonormal_rows(M, n, lv.lo.data(), lv.hi.data(), lv.S.data())) return false;
  if (!bound_clears(lv.S.data(), n, n, tol.top, tol.floor, 0.0, lv.work.data())) {
    small::gram_rows(M, nv, n, k_, lv.A.data(), n, lv.lo.data(), lv.hi.data());
    if (!factor_shifted(lv.A.data(), n, n, -tol.floor, Gs_.data(), nv)) return false;
  }
  double* y = lv.y.data();  // L y = rest, column by column
  for (int i = 0; i < n; ++i) y[i] = lv.rest[i];
  const double* L = lv.S.data();
  for (int j = 0; j < n; ++j) {
    y[j] /= L[j * n + j];
    small::sub_scaled(y[j], L + j * n + j + 1, y + j + 1, n - j - 1);
  }
  small::combine_rows(y, P_.data(), nv, n, tk_.data(), k_);  // x = Q^T y
  q_ready_ = true;
  return true;
}

// n > k: x = (M^T M + lambda_0^2 I)^-1 M^T rest when M^T M's (k x k) eigenvalues clear the
// floor: JN JN^T's nonzero eigenvalues are M^T M's.
bool Law::solve_columns(Level& lv, const double* M, const Tolerances& tol) {
  const int n = static_cast<int>(lv.rest.size()), k = k_, nv = static_cast<int>(Z_.rows());
  small::gram_columns(M, nv, n, k, G_.data(), nv, lv.work.data());
  if (!factor_regular(G_.data(), nv, k, tol.floor, tol.d2, Gs_.data(), nv, lv.work.data())) {
    return false;
  }
  times_rows(M, n, lv.rest.data());
  small::cholesky_solve(Gs_.data(), nv, k, tk_.data());
  return true;
}

// The damping band (or a basis level not regular): x from the eigenpairs of M M^T; for a
// basis level, P_ gets JN's row space above the tolerances, M^T V diag(1 / sqrt(w))
// (orthonormal), at most k directions, the largest (w ascends). Returns their count.
int Law::solve_eigenpairs(Level& lv, const double* M, const Tolerances& tol) {
  const int n = static_cast<int>(lv.rest.size()), k = k_, nv = static_cast<int>(Z_.rows());
  small::gram_rows(M, nv, n, k, lv.A.data(), n);
  int p = 0;
  auto by_eigenpairs = [&](auto& eig) {
    eig.compute(lv.A);
    const auto& V = eig.eigenvectors();
    const auto& w = eig.eigenvalues();
    for (int i = 0; i < n; ++i) {
      const double wi = std::max(w[i], tol.eps2) + tol.d2;
      lv.tmp[i] = wi > 0.0 ? wi : std::numeric_limits<double>::infinity();
    }
    lv.y.noalias() = V.transpose() * lv.rest;
    lv.y.array() /= lv.tmp.array();
    lv.tmp.noalias() = V * lv.y;
    times_rows(M, n, lv.tmp.data());
    if (!lv.basis) return;
    for (int i = n - 1; i >= 0; --i) {
      if (w[i] > tol.kept && p < k) {
        auto col = P_.col(p).head(k);
        col.setZero();
        for (int r = 0; r < n; ++r) {
          small::sub_scaled(-V(r, i) / std::sqrt(w[i]), M + r * nv, col.data(), k);
        }
        ++p;
      }
    }
  };
  // A fixed-capacity solver allocates nothing (Eigen's dynamic one allocates a
  // workspace in each tridiagonalisation).
  if (n <= MAX_EIGEN_ROWS) {
    by_eigenpairs(lv.eig_small);
  } else {
    by_eigenpairs(lv.eig);
  }
  return p;
}

// The products of this file are small (at most a few tens of rows and joints): lazy
// (coefficient-based) products, without the packing of Eigen's general matrix product.
double Law::prioritized_levels(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot) {
  const int m = ext.m, v = r - m, nv = ext.nv;
  const int L = static_cast<int>(ends_.size());
  ext.demand(r, b_);
  bool finite = small::all_finite(ext.J.data() + m * nv, v * nv) && small::all_finite(b_.data(), r);
  for (int l = 0, start = 0; l < L; start = ends_[l++]) {  // each level's scale; J's finiteness
    lscale_[l] = rows_scale(ext.J.data() + start * nv, ends_[l] - start, nv, scan_rows_, finite,
                            jlo_.data() + start, jhi_.data() + start);
  }
  for (const Vec& z : z_) finite = finite && small::all_finite(z.data(), nv);
  if (!finite) {
    qdot.setConstant(std::numeric_limits<double>::quiet_NaN());
    parts_.setConstant(std::numeric_limits<double>::quiet_NaN());
    qdot_c_ = parts_.row(0).transpose();
    return 0.0;
  }
  parts_.setZero();
  double blocked = 0.0;
  if (unit_plan_ && projected_levels(ext, v, blocked)) {
    qdot = out_;
    qdot_c_ = parts_.row(0).transpose();
    return blocked;
  }
  if (unit_plan_) parts_.setZero();  // the general form below, from the start
  k_ = nv;
  z_identity_ = true;
  const int e1 = ends_[0];
  const double scale1 = lscale_[0];
  if (v > 0) level_constraints(ext, v, scale1);
  out_ = parts_.row(0).transpose();
  int start = 0;
  for (int l = 0; l < L; ++l) {
    Level& lv = level_[static_cast<size_t>(l)];
    const int n = ends_[l] - start;
    const auto Jl = ext.J.middleRows(start, n);
    if (l == 0 && v == 0) {  // nothing above level 1 moves: out_ = 0
      lv.rest = b_.head(n);
    } else {
      for (int i = 0; i < n; ++i) lv.rest[i] = b_[start + i] - row_times(ext, start + i, out_);
    }
    Eigen::Map<Vec> part(parts_.row(1 + l).data(), nv);
    solve_level(lv, Jl.data(), jlo_.data() + start, jhi_.data() + start, lscale_[l],
                part.data());
    if (l == 0 && !s_.budget_blocks) {  // measured on the law's own demand
      zp_ = out_ + part;
      blocked = unrealised_rows(ext, 0, e1, zp_);
    }
    budget(part, s_.dt);
    for (size_t o = 0; o < zlevel_.size(); ++o) {  // N z = Z Z^T z, within the budget
      if (zlevel_[o] != l + 1) continue;
      if (z_identity_) {
        zp_ = z_[o];
      } else if (k_ == 0) {
        zp_.setZero();
      } else {
        zp_.setZero();
        for (int j = 0; j < k_; ++j) {
          const double* zc = Z_.data() + j * nv;
          small::sub_scaled(-small::dot(zc, z_[o].data(), nv), zc, zp_.data(), nv);
        }
      }
      budget(zp_, s_.dt);
      part += zp_;
    }
    out_ += part;
    if (l == 0 && s_.budget_blocks) blocked = unrealised_rows(ext, 0, e1, out_);
    start = ends_[l];
  }
  qdot = out_;
  qdot_c_ = parts_.row(0).transpose();
  return blocked;
}

// |b - J x| / |b| on rows [a, b) (b_ holds the demand): 0 when realised exactly.
double Law::unrealised_rows(const ExtendedTask& ext, int a, int b, const Vec& x) {
  const auto bt = b_.segment(a, b - a);
  const double demand = bt.norm();
  if (demand == 0.0) return 0.0;
  double left = 0.0;
  for (int i = a; i < b; ++i) {
    const double r = b_[i] - row_times(ext, i, x);
    left += r * r;
  }
  return std::sqrt(left) / demand;
}

// J's row i (a task row) times x, where the row may not be zero (rows_scale's windows).
double Law::row_times(const ExtendedTask& ext, int i, const Vec& x) const {
  const int from = jlo_[static_cast<size_t>(i)], to = jhi_[static_cast<size_t>(i)];
  return from < to ? small::dot(ext.J.row(i).data() + from, x.data() + from, to - from) : 0.0;
}

}  // namespace clik
