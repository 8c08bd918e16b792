// Dense kernels for the small matrices of law (10) by levels (loop/levels.cpp): a few
// tens of rows and joints, where the dispatch of Eigen's dynamic-size expressions costs
// more than their arithmetic. Plain loops on raw columns (column-major, a leading
// dimension ld), two doubles at a time, no allocation.
#pragma once

#include <algorithm>
#include <cmath>

namespace clik::small {

// Two doubles at once (SSE2 on x86-64, NEON on arm64: GCC's and Clang's vector
// extension), loaded from and stored to any double's address.
typedef double Pair __attribute__((vector_size(16), aligned(8), may_alias));

inline Pair load(const double* p) { return *reinterpret_cast<const Pair*>(p); }
inline void store(double* p, Pair v) { *reinterpret_cast<Pair*>(p) = v; }

// sum_i a[i] b[i]
inline double dot(const double* a, const double* b, int n) {
  Pair s0 = {0.0, 0.0}, s1 = {0.0, 0.0};
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    s0 += load(a + i) * load(b + i);
    s1 += load(a + i + 2) * load(b + i + 2);
  }
  if (i + 2 <= n) {
    s0 += load(a + i) * load(b + i);
    i += 2;
  }
  s0 += s1;
  double s = s0[0] + s0[1];
  if (i < n) s += a[i] * b[i];
  return s;
}

// y = x (n, not overlapping): inline, where std::copy calls memmove
inline void copy(const double* x, double* y, int n) {
  int i = 0;
  for (; i + 2 <= n; i += 2) store(y + i, load(x + i));
  if (i < n) y[i] = x[i];
}

// y -= alpha x (x and y do not overlap)
inline void sub_scaled(double alpha, const double* x, double* y, int n) {
  const Pair a = {alpha, alpha};
  int i = 0;
  for (; i + 2 <= n; i += 2) store(y + i, load(y + i) - a * load(x + i));
  if (i < n) y[i] -= alpha * x[i];
}

// y -= sum_t a[t] X_t (y += with Add) over the m rows X_t = X + t * ldx (none
// overlapping y): four rows at a time, y loaded and stored once per four.
template <bool Add = false>
inline void sub_rows(const double* a, const double* X, int ldx, int m, double* y, int n) {
  auto put = [](double* p, Pair s) { store(p, Add ? load(p) + s : load(p) - s); };
  auto put1 = [](double* p, double s) { *p = Add ? *p + s : *p - s; };
  int t = 0;
  for (; t + 4 <= m; t += 4) {
    const double *x0 = X + t * ldx, *x1 = x0 + ldx, *x2 = x1 + ldx, *x3 = x2 + ldx;
    const Pair a0 = {a[t], a[t]}, a1 = {a[t + 1], a[t + 1]};
    const Pair a2 = {a[t + 2], a[t + 2]}, a3 = {a[t + 3], a[t + 3]};
    int i = 0;
    for (; i + 2 <= n; i += 2) {
      put(y + i, (a0 * load(x0 + i) + a1 * load(x1 + i)) + (a2 * load(x2 + i) + a3 * load(x3 + i)));
    }
    if (i < n) put1(y + i, (a[t] * x0[i] + a[t + 1] * x1[i]) + (a[t + 2] * x2[i] + a[t + 3] * x3[i]));
  }
  if (t + 2 <= m) {
    const double *x0 = X + t * ldx, *x1 = x0 + ldx;
    const Pair a0 = {a[t], a[t]}, a1 = {a[t + 1], a[t + 1]};
    int i = 0;
    for (; i + 2 <= n; i += 2) put(y + i, a0 * load(x0 + i) + a1 * load(x1 + i));
    if (i < n) put1(y + i, a[t] * x0[i] + a[t + 1] * x1[i]);
    t += 2;
  }
  if (t < m) {
    const double* x0 = X + t * ldx;
    const Pair a0 = {a[t], a[t]};
    int i = 0;
    for (; i + 2 <= n; i += 2) put(y + i, a0 * load(x0 + i));
    if (i < n) put1(y + i, a[t] * x0[i]);
  }
}

// y = sum_t a[t] X_t (n values).
inline void combine_rows(const double* a, const double* X, int ldx, int m, double* y, int n) {
  std::fill(y, y + n, 0.0);
  sub_rows<true>(a, X, ldx, m, y, n);
}

// [lo, hi): where the n values at x are not zero; lo = n, hi = 0 for none (so that
// unions by min and max leave it out, and intersections are empty).
inline void nonzero_range(const double* x, int n, int& lo, int& hi) {
  lo = 0;
  while (lo < n && x[lo] == 0.0) ++lo;
  hi = n;
  while (hi > lo && x[hi - 1] == 0.0) --hi;
  if (lo == hi) {
    lo = n;
    hi = 0;
  }
}

// C(i, j) = A_i . B_j (i < na, j < nb) for the rows A_i = A + i * lda, B_j = B + j * ldb
// of length n, C(i, j) at C + i * ldc + j; two rows of each at a time (four sums share
// their loads). With symmetric (A = B, na = nb), only j <= i, mirrored. With lo and hi,
// A's row i is zero outside [lo[i], hi[i]) (B's too when symmetric): each sum runs where
// its rows may not be zero (the rows of tasks on different branches of a tree share
// none; a posture row has one joint).
inline void row_dots(const double* A, int lda, int na, const double* B, int ldb, int nb, int n,
                     double* C, int ldc, bool symmetric, const int* lo = nullptr,
                     const int* hi = nullptr) {
  auto sum = [](Pair s) { return s[0] + s[1]; };
  for (int i = 0; i < na; i += 2) {
    const bool two = i + 1 < na;
    const double *a0 = A + i * lda, *a1 = two ? a0 + lda : a0;
    const int last = symmetric ? i + 1 : nb;
    for (int j = 0; j < last; j += 2) {
      const bool pair = j + 1 < nb;
      const double *b0 = B + j * ldb, *b1 = pair ? b0 + ldb : b0;
      int from = 0, to = n;
      if (lo != nullptr) {  // A's two rows' union (and B's, when symmetric): intersected
        const int ia = two ? i + 1 : i, jb = pair ? j + 1 : j;
        from = std::min(lo[i], lo[ia]);
        to = std::max(hi[i], hi[ia]);
        if (symmetric) {
          from = std::max(from, std::min(lo[j], lo[jb]));
          to = std::min(to, std::max(hi[j], hi[jb]));
        }
      }
      Pair s00 = {0.0, 0.0}, s01 = s00, s10 = s00, s11 = s00;
      int c = from;
      for (; c + 2 <= to; c += 2) {
        const Pair u0 = load(a0 + c), u1 = load(a1 + c), v0 = load(b0 + c), v1 = load(b1 + c);
        s00 += u0 * v0;
        s01 += u0 * v1;
        s10 += u1 * v0;
        s11 += u1 * v1;
      }
      double c00 = sum(s00), c01 = sum(s01), c10 = sum(s10), c11 = sum(s11);
      if (c < to) {
        c00 += a0[c] * b0[c];
        c01 += a0[c] * b1[c];
        c10 += a1[c] * b0[c];
        c11 += a1[c] * b1[c];
      }
      C[i * ldc + j] = c00;
      if (pair) C[i * ldc + j + 1] = c01;
      if (two) C[(i + 1) * ldc + j] = c10;
      if (two && pair) C[(i + 1) * ldc + j + 1] = c11;
    }
  }
  if (!symmetric) return;
  for (int i = 0; i < na; ++i) {
    for (int j = i + 1; j < na; ++j) C[i * ldc + j] = C[j * ldc + i];
  }
}

// x *= alpha
inline void scale(double alpha, double* x, int n) {
  const Pair a = {alpha, alpha};
  int i = 0;
  for (; i + 2 <= n; i += 2) store(x + i, load(x + i) * a);
  if (i < n) x[i] *= alpha;
}

// y -= x * x, coefficient-wise
inline void sub_squares(const double* x, double* y, int n) {
  int i = 0;
  for (; i + 2 <= n; i += 2) store(y + i, load(y + i) - load(x + i) * load(x + i));
  if (i < n) y[i] -= x[i] * x[i];
}

// Whether the n values at x are all finite (x * 0 is NaN for a NaN or an infinity).
inline bool all_finite(const double* x, int n) {
  Pair zero = {0.0, 0.0};
  const Pair none = {0.0, 0.0};
  int i = 0;
  for (; i + 2 <= n; i += 2) zero += load(x + i) * none;
  double z = zero[0] + zero[1];
  if (i < n) z += x[i] * 0.0;
  return z == 0.0;
}

// In-place Cholesky factorisation A = L L^T of the n x n lower triangle of A (column j
// at A + j * ld, rows j to n - 1: contiguous); the upper triangle is not read.
// Right-looking by panels of up to four columns: a panel is factorised, then the columns
// after it are updated by all of its columns in one pass each (sub_rows). False when A
// is not positive definite (a pivot <= 0).
inline bool cholesky(double* A, int ld, int n) {
  double a[4];
  for (int j = 0; j < n; j += 4) {
    const int w = n - j < 4 ? n - j : 4;
    double* c0 = A + j * ld;  // the panel's first column
    for (int t = 0; t < w; ++t) {
      double* ct = c0 + t * ld;  // column j + t, rows j + t to n - 1
      const int r = j + t;
      int f = t;
      for (int u = 0; u < t; ++u) {
        a[u] = c0[u * ld + r];  // L(r, j + u)
        if (f == t && a[u] != 0.0) f = u;
      }
      sub_rows(a + f, c0 + f * ld + r, ld, t - f, ct + r, n - r);
      if (!(ct[r] > 0.0)) return false;
      ct[r] = std::sqrt(ct[r]);
      scale(1.0 / ct[r], ct + r + 1, n - r - 1);
    }
    for (int c = j + w; c < n; ++c) {  // L(c, j + u) = 0 for u < f: no update from them
      int f = w;
      for (int u = 0; u < w; ++u) {
        a[u] = c0[u * ld + c];  // L(c, j + u)
        if (f == w && a[u] != 0.0) f = u;
      }
      if (f < w) sub_rows(a + f, c0 + f * ld + c, ld, w - f, A + c * ld + c, n - c);
    }
  }
  return true;
}

// x = (L L^T)^-1 b in place (L from cholesky()).
inline void cholesky_solve(const double* L, int ld, int n, double* b) {
  for (int j = 0; j < n; ++j) {  // L y = b, column by column
    const double* col = L + j * ld;
    b[j] /= col[j];
    sub_scaled(b[j], col + j + 1, b + j + 1, n - j - 1);
  }
  for (int j = n - 1; j >= 0; --j) {  // L^T x = y: row j of L^T is column j of L
    const double* col = L + j * ld;
    b[j] = (b[j] - dot(col + j + 1, b + j + 1, n - j - 1)) / col[j];
  }
}

// A lower bound on the smallest eigenvalue of L L^T (L lower triangular, n x n, column j
// at L + j * ld, a positive diagonal): 1 / (|x|_inf |y|_inf) with C x = e and C^T y = e,
// C the comparison matrix of L (|l_ii| on the diagonal, -|l_ij| below). |L^-1| <= C^-1
// entrywise, so |L^-1|_inf <= |x|_inf and |L^-1|_1 <= |y|_inf, and
// |L^-1|_2^2 <= |L^-1|_1 |L^-1|_inf (Higham, Accuracy and Stability of Numerical
// Algorithms, 2002, sec. 8.3). Two triangular solves; work holds 2 n.
inline double eigen_lower_bound(const double* L, int ld, int n, double* work) {
  typedef long long Bits __attribute__((vector_size(16), aligned(8), may_alias));
  const Bits magnitude = {0x7fffffffffffffffLL, 0x7fffffffffffffffLL};
  auto abs2 = [&](Pair v) { return reinterpret_cast<Pair>(reinterpret_cast<Bits>(v) & magnitude); };
  double *x = work, *y = work + n;
  std::fill(x, x + n, 1.0);
  double top_x = 0.0, top_y = 0.0;
  for (int j = 0; j < n; ++j) {  // C x = e, column by column
    const double* col = L + j * ld;
    const double xj = x[j] / col[j];
    x[j] = xj;
    top_x = std::max(top_x, xj);
    const Pair p = {xj, xj};
    int i = j + 1;
    for (; i + 2 <= n; i += 2) store(x + i, load(x + i) + abs2(load(col + i)) * p);
    if (i < n) x[i] += std::abs(col[i]) * xj;
  }
  for (int j = n - 1; j >= 0; --j) {  // C^T y = e: y_j = (1 + sum_i>j |l_ij| y_i) / l_jj
    const double* col = L + j * ld;
    Pair s2 = {0.0, 0.0};
    int i = j + 1;
    for (; i + 2 <= n; i += 2) s2 += abs2(load(col + i)) * load(y + i);
    double s = 1.0 + s2[0] + s2[1];
    if (i < n) s += std::abs(col[i]) * y[i];
    y[j] = s / col[j];
    top_y = std::max(top_y, y[j]);
  }
  return 1.0 / (top_x * top_y);
}

// A = R R^T (n x n, both triangles) of the n rows of R, row i at R + i * ldr (zero
// outside [lo[i], hi[i]) when given).
inline void gram_rows(const double* R, int ldr, int n, int cols, double* A, int ld,
                      const int* lo = nullptr, const int* hi = nullptr) {
  row_dots(R, ldr, n, R, ldr, n, cols, A, ld, true, lo, hi);
}

// G = R^T R (cols x cols, both triangles) of the n rows of R (row i at R + i * ldr):
// column a of G's lower triangle is sum_i R(i, a) R(i, 0..a), the rows combined four at
// a time (sub_rows: no chain of dependent sums). col holds n values (R's column a).
inline void gram_columns(const double* R, int ldr, int n, int cols, double* G, int ld,
                         double* col) {
  for (int a = 0; a < cols; ++a) {
    for (int i = 0; i < n; ++i) col[i] = R[i * ldr + a];
    double* g = G + a * ld;
    std::fill(g, g + a + 1, 0.0);
    sub_rows<true>(col, R, ldr, n, g, a + 1);
  }
  for (int a = 0; a < cols; ++a) {
    for (int b = 0; b < a; ++b) G[b * ld + a] = G[a * ld + b];
  }
}

// The orthogonal complement of the p columns of P (k x p, rank p; overwritten by
// Householder vectors): W (k x (k - p), orthonormal columns) = H_0 ... H_{p-1}'s last
// k - p columns, where H_j = I - beta_j v_j v_j^T takes P to upper-triangular form.
// beta (p) is a workspace.
inline void householder_complement(double* P, int ldp, int k, int p, double* beta, double* W,
                                   int ldw) {
  for (int j = 0; j < p; ++j) {
    double* v = P + j * ldp + j;  // v_j = P(j:k, j) - alpha e_0
    const int len = k - j;
    const double norm = std::sqrt(dot(v, v, len));
    if (norm == 0.0) {
      beta[j] = 0.0;
      continue;
    }
    const double x0 = std::abs(v[0]);
    v[0] += v[0] > 0.0 ? norm : -norm;
    beta[j] = 1.0 / (norm * (norm + x0));  // 2 / |v|^2, |v|^2 = 2 |x| (|x| + |x_0|)
    for (int c = j + 1; c < p; ++c) {
      double* col = P + c * ldp + j;
      sub_scaled(beta[j] * dot(v, col, len), v, col, len);
    }
  }
  const int q = k - p;
  for (int c = 0; c < q; ++c) {
    double* col = W + c * ldw;
    for (int i = 0; i < k; ++i) col[i] = i == p + c ? 1.0 : 0.0;
    for (int j = p - 1; j >= 0; --j) {
      if (beta[j] == 0.0) continue;
      const double* v = P + j * ldp + j;
      sub_scaled(beta[j] * dot(v, col + j, k - j), v, col + j, k - j);
    }
  }
}

}  // namespace clik::small
