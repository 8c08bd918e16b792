// Law (10) on two levels whose second holds unit rows (a posture task: one joint per
// row), without the basis Z of the free directions: docs/method.md, "Several tasks", "A
// posture below the hands". The same velocity as Law::prioritized_levels' general form
// (loop/levels.cpp), at a cost close to level 1's Gram matrix.
//
// With the constraint rows unit rows too (joint ranges: a joint held), the directions
// they leave are the free joints F; level 1's rows on F are M1 (n1 x f), L L^T = M1 M1^T,
// N1 = I - M1^T (M1 M1^T)^-1 M1 the projector on their complement. Level 2 selects the
// joints S' of F (D = S'^T S'); with E = F \ S' and P = L^-1 M1[:, E],
//   JN^T (JN JN^T + d2 I)^-1 r = (g + N1 E^T (P^T P + d2 I)^-1 E g) / (1 + d2),
//   g = N1 S'^T r,
// Woodbury's identity on (N1 - N1 E^T E N1 + d2 I) restricted to the range of N1; P^T P's
// eigenvalues are those of the general form's Gram matrix Z^T D Z (with 1s), so the
// regular case is the same test. Anything else (a constraint row on several joints, a
// level not regular, level 2 of fewer rows than free directions) returns false: the
// general form runs.
#include <algorithm>
#include <cmath>
#include <limits>

#include "loop/laws.hpp"
#include "loop/regular_factor.hpp"
#include "loop/small_dense.hpp"

namespace clik {

namespace {

// The column of a row of n values with one nonzero entry, +1 or -1 (its sign into
// sign); -1 otherwise.
int unit_column(const double* row, int n, double& sign) {
  int col = -1;
  for (int c = 0; c < n; ++c) {
    if (row[c] == 0.0) continue;
    if (col >= 0 || (row[c] != 1.0 && row[c] != -1.0)) return -1;
    col = c;
    sign = row[c];
  }
  return col;
}

// x = L^-1 x in place (L lower, n x n, column j at L + j * n; inv its diagonal's
// inverses), column by column.
void forward(const double* L, const double* inv, int n, double* x) {
  for (int j = 0; j < n; ++j) {
    x[j] *= inv[j];
    small::sub_scaled(x[j], L + j * n + j + 1, x + j + 1, n - j - 1);
  }
}

// Y = L^-1 Y in place for the n rows of Y (each of ld values, leading dimension ld): row
// i is (Y_i - sum_{t<i} L(i, t) Y_t) / L(i, i), the earlier rows combined four at a time.
// a holds n values.
void forward_rows(const double* L, const double* inv, int n, double* Y, int ld, double* a) {
  for (int i = 0; i < n; ++i) {
    for (int t = 0; t < i; ++t) a[t] = L[t * n + i];
    double* row = Y + i * ld;
    small::sub_rows(a, Y, ld, i, row, ld);
    small::scale(inv[i], row, ld);
  }
}

}  // namespace

// x = N1 x (f values): x - M1^T (L L^T)^-1 M1 x (inv: L's diagonal's inverses).
void Law::project_free(const double* M1, int n1, int f, const double* L, const double* inv,
                       double* x) {
  const int nv = static_cast<int>(u_.size());
  double* y = s1_.data();
  const Level& lv = level_[0];
  for (int i = 0; i < n1; ++i) {
    const int lo = lv.lo[i], hi = lv.hi[i];
    y[i] = lo < hi ? small::dot(M1 + i * nv + lo, x + lo, hi - lo) : 0.0;
  }
  forward(L, inv, n1, y);
  for (int j = n1 - 1; j >= 0; --j) {  // L^T y = y: row j of L^T is column j of L
    y[j] = (y[j] - small::dot(L + j * n1 + j + 1, y + j + 1, n1 - j - 1)) * inv[j];
  }
  small::sub_rows(y, M1, nv, n1, x, f);
}

// S = the factor of A + d2 I (n x n) when A's eigenvalues clear the floor. The test is
// carried from sample to sample: a factorisation of A - c I (c >= floor) shows
// lambda_min(A) > c, and by Weyl's inequality lambda_min moves by at most |A - A_prev|_F
// from one sample to the next, so while c less the drift since (and the rounding of
// factor_regular's bound) clears the floor, A + d2 I's factorisation alone does.
// c is a quarter of the smallest pivot when that factorises (a margin), else the floor.
bool Law::regular_level(const double* A, int n, double floor, double d2, double* S) {
  double* before = A1_.data();
  double drift = 0.0, top = 0.0;
  for (int i = 0; i < n * n; ++i) {
    const double d = A[i] - before[i];
    drift += d * d;
    before[i] = A[i];
  }
  for (int j = 0; j < n; ++j) top = std::max(top, A[j * n + j] + d2);
  const double rounding = 2.0 * (n + 1) * n * std::numeric_limits<double>::epsilon() * top;
  certified_ -= std::sqrt(drift);
  if (!factor_shifted(A, n, n, d2, S, n)) {
    certified_ = -1.0;
    return false;
  }
  if (certified_ - rounding > floor) return true;
  // a margin: try c between the floor and the smallest pivot (an upper bound on
  // lambda_min), where the last try succeeded or halfway (geometrically) below a failure
  double pivot = std::numeric_limits<double>::infinity();
  for (int j = 0; j < n; ++j) pivot = std::min(pivot, S[j * n + j] * S[j * n + j] - d2);
  double* scratch = Hs_.data();
  const double c = std::min(margin_ > 0.0 ? margin_ : 0.5 * pivot, 0.5 * pivot);
  if (c > floor && factor_shifted(A, n, n, -c, scratch, n)) {
    certified_ = c;
    margin_ = std::min(2.0 * c, 0.5 * pivot);
    return true;
  }
  margin_ = c > floor ? std::sqrt(c * floor) : 0.0;
  if (!factor_shifted(A, n, n, -floor, scratch, n)) {
    certified_ = -1.0;
    return false;
  }
  certified_ = floor;
  return true;
}

bool Law::projected_levels(const ExtendedTask& ext, int v, double& blocked) {
  const int m = ext.m, nv = ext.nv, n1 = ends_[0], n2 = ends_[1] - n1;
  const double d2 = s_.damping * s_.damping;
  const double scale1 = lscale_[0];
  // the constraint level: unit rows, each holding one joint
  std::fill(fpos_.begin(), fpos_.end(), 0);
  if (v > 0) {
    const double eps = CONDITION_RATIO * scale1;
    if (!(1.0 > RANK_TOLERANCE * std::max(scale1, 1.0))) return false;
    const double gain = 1.0 / (std::max(1.0, eps * eps) + d2);
    double* part = parts_.row(0).data();
    for (int r = 0; r < v; ++r) {
      double sign = 0.0;
      const int c = unit_column(ext.J.row(m + r).data(), nv, sign);
      if (c < 0 || fpos_[c] < 0) return false;
      fpos_[c] = -1;
      part[c] = gain * b_[m + r] * sign;
    }
    budget(parts_.row(0), s_.dt);
  }
  int f = 0;
  for (int c = 0; c < nv; ++c) {
    if (fpos_[c] < 0) continue;
    fpos_[c] = f;
    fcols_[f++] = c;
  }
  const int k = f - n1;  // free directions below level 1 (regular: rank n1)
  if (k < 0 || n2 <= k) return false;
  for (int i = 0; i < n2; ++i) {  // level 2's rows: one joint each, +1 or -1, distinct
    const double a = ext.J(n1 + i, jlo_[n1 + i]);
    if (a != 1.0 && a != -1.0) return false;
  }
  out_ = parts_.row(0).transpose();
  // level 1 on F
  Level& l1 = level_[0];
  const double* M1 = ext.J.data();
  if (v == 0) {
    std::copy(jlo_.begin(), jlo_.begin() + n1, l1.lo.begin());
    std::copy(jhi_.begin(), jhi_.begin() + n1, l1.hi.begin());
    l1.rest = b_.head(n1);
  } else {
    for (int i = 0; i < n1; ++i) {
      const double* row = ext.J.row(i).data();
      double* to = M1_.row(i).data();
      for (int p = 0; p < f; ++p) to[p] = row[fcols_[p]];
      small::nonzero_range(to, f, l1.lo[i], l1.hi[i]);
      l1.rest[i] = b_[i] - row_times(ext, i, out_);
    }
    M1 = M1_.data();
  }
  const double keep = RANK_TOLERANCE * std::max(scale1, 1.0);
  const double eps2 = std::pow(CONDITION_RATIO * scale1, 2);
  const double floor1 = std::max(eps2, std::max(keep * keep, GRAM_TOLERANCE * scale1 * scale1));
  small::gram_rows(M1, nv, n1, f, l1.A.data(), n1, l1.lo.data(), l1.hi.data());
  if (!regular_level(l1.A.data(), n1, floor1, d2, l1.S.data())) return false;
  l1.y = l1.rest;
  small::cholesky_solve(l1.S.data(), n1, n1, l1.y.data());
  double* x = g_.data();
  small::combine_rows(l1.y.data(), M1, nv, n1, x, f);
  Eigen::Map<Vec> part1(parts_.row(1).data(), nv);
  for (int p = 0; p < f; ++p) part1[fcols_[p]] = x[p];
  if (d2 > 0.0 && !factor_shifted(l1.A.data(), n1, n1, 0.0, l1.S.data(), n1)) return false;
  const double* L = l1.S.data();  // M1 M1^T = L L^T
  double* inv = s1_.data() + nv;  // its diagonal's inverses
  for (int i = 0; i < n1; ++i) inv[i] = 1.0 / L[i * n1 + i];
  // level 2: u = S'^T rest, g = N1 u
  Level& l2 = level_[1];
  std::fill(hit_.begin(), hit_.begin() + f, 0);
  std::fill(u_.data(), u_.data() + f, 0.0);
  // level 2's demand after level 1 (the general form's order: budget, then the demand)
  if (!s_.budget_blocks) {
    zp_ = out_ + part1;
    blocked = unrealised_rows(ext, 0, n1, zp_);
  }
  budget(part1, s_.dt);
  out_ += part1;
  if (s_.budget_blocks) blocked = unrealised_rows(ext, 0, n1, out_);
  for (int i = 0; i < n2; ++i) {
    const int row = n1 + i, c = jlo_[row];
    l2.rest[i] = b_[row] - row_times(ext, row, out_);
    const int p = fpos_[c];
    if (p < 0) continue;  // a held joint: a zero row of JN
    if (hit_[p]) return false;
    hit_[p] = 1;
    u_[p] = ext.J(row, c) * l2.rest[i];
  }
  // E: the free joints level 2 does not select; P = L^-1 M1[:, E], H = P^T P
  int e = 0;
  for (int p = 0; p < f; ++p) {
    if (!hit_[p]) epos_[e++] = p;
  }
  double* t = t_.data();  // u + E^T (P^T P + d2 I)^-1 E g, g = N1 u
  std::copy(u_.data(), u_.data() + f, t);
  if (e > 0) {
    const double scale2 = lscale_[1];
    const double floor2 = std::pow(CONDITION_RATIO * scale2, 2);
    // Y = L^-1 [M1[:, E], M1 u] (n1 rows of e + 1 values, leading dimension ldy): P's rows
    // and z = L^-1 M1 u, so that Y^T Y holds H = P^T P and P^T z
    const int ey = e + 1, ldy = (ey + 1) & ~1;
    double* Y = Pe_.data();
    for (int i = 0; i < n1; ++i) {
      double* row = Y + i * ldy;
      const double* m1 = M1 + i * nv;
      for (int j = 0; j < e; ++j) row[j] = m1[epos_[j]];
      const int lo = l1.lo[i], hi = l1.hi[i];
      row[e] = lo < hi ? small::dot(m1 + lo, u_.data() + lo, hi - lo) : 0.0;
      if (ey < ldy) row[ey] = 0.0;
    }
    forward_rows(L, inv, n1, Y, ldy, g_.data());
    small::gram_columns(Y, ldy, n1, ey, H_.data(), nv, s1_.data());
    double* w = zp_.data();  // E g = u_E - P^T z, then (P^T P + d2 I)^-1 E g
    for (int j = 0; j < e; ++j) w[j] = u_[epos_[j]] - H_(e, j);
    if (!factor_regular(H_.data(), nv, e, floor2, d2, Hs_.data(), nv, l2.work.data(),
                        Hs_.data() + nv * nv)) {
      return false;
    }
    small::cholesky_solve(Hs_.data(), nv, e, w);
    for (int j = 0; j < e; ++j) t[epos_[j]] += w[j];
  }
  project_free(M1, n1, f, L, inv, t);
  Eigen::Map<Vec> part2(parts_.row(2).data(), nv);
  const double a = 1.0 / (1.0 + d2);
  for (int p = 0; p < f; ++p) part2[fcols_[p]] = a * t[p];
  budget(part2, s_.dt);
  out_ += part2;
  return true;
}

}  // namespace clik
