// Dense kernels for the small matrices of law (10) by levels (loop/levels.cpp): a few
// tens of rows and joints, where the dispatch of Eigen's dynamic-size expressions costs
// more than their arithmetic. Plain loops on raw columns (column-major, a leading
// dimension ld), two doubles at a time, no allocation.
#pragma once

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

// y -= alpha x (x and y do not overlap)
inline void sub_scaled(double alpha, const double* x, double* y, int n) {
  const Pair a = {alpha, alpha};
  int i = 0;
  for (; i + 2 <= n; i += 2) store(y + i, load(y + i) - a * load(x + i));
  if (i < n) y[i] -= alpha * x[i];
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

// In-place Cholesky factorisation A = U^T U of the n x n upper triangle of A (column j
// of U above its diagonal is row j of L = U^T, contiguous: every sum is a dot product
// of two columns); the lower triangle is not read. False when A is not positive
// definite (a pivot <= 0).
inline bool cholesky(double* A, int ld, int n) {
  for (int j = 0; j < n; ++j) {
    double* cj = A + j * ld;  // U(0:j+1, j)
    for (int i = 0; i < j; ++i) {
      const double* ci = A + i * ld;
      cj[i] = (cj[i] - dot(ci, cj, i)) / ci[i];
    }
    const double pivot = cj[j] - dot(cj, cj, j);
    if (!(pivot > 0.0)) return false;
    cj[j] = std::sqrt(pivot);
  }
  return true;
}

// x = (U^T U)^-1 b in place (U from cholesky()).
inline void cholesky_solve(const double* U, int ld, int n, double* b) {
  for (int j = 0; j < n; ++j) {  // U^T y = b: row j of U^T is column j of U
    b[j] = (b[j] - dot(U + j * ld, b, j)) / U[j * ld + j];
  }
  for (int j = n - 1; j >= 0; --j) {  // U x = y, column by column
    b[j] /= U[j * ld + j];
    sub_scaled(b[j], U + j * ld, b, j);
  }
}

// A = R R^T (n x n, both triangles) of the n rows of R, row i at R + i * ldr.
inline void gram_rows(const double* R, int ldr, int n, int cols, double* A, int ld) {
  for (int j = 0; j < n; ++j) {
    for (int i = j; i < n; ++i) {
      const double s = dot(R + i * ldr, R + j * ldr, cols);
      A[j * ld + i] = s;
      A[i * ld + j] = s;
    }
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
