// The basis Z of the directions law (10)'s levels leave free (loop/levels.cpp): Z loses
// a level's row space (Householder reflections, or the pivoted Cholesky factorisation of
// the projector on the complement of Q's rows), and a level's rows are orthonormalised
// (modified Gram-Schmidt, M = L Q). docs/method.md, "In the free directions'
// coordinates".
#include <algorithm>
#include <cmath>

#include "loop/laws.hpp"
#include "loop/small_dense.hpp"

namespace clik {

// Z <- Z W: the free directions W_'s first q columns (orthonormal, in Z's coordinates)
// describe.
void Law::set_free(int q) {
  const int k = k_, nv = static_cast<int>(Z_.rows());
  if (z_identity_) {
    Z_.leftCols(q) = W_.topLeftCorner(k, q);
  } else {  // Z W, column by column
    for (int c = 0; c < q; ++c) {
      small::combine_rows(W_.data() + c * nv, Z_.data(), nv, k, Zn_.data() + c * nv, nv);
    }
    Z_.leftCols(q) = Zn_.leftCols(q);
  }
  k_ = q;
  z_identity_ = false;
}

// Z loses the directions in P_'s first p columns (k_ x p, of rank p, in Z's
// coordinates): Householder reflections H_0 ... H_{p-1} take P to upper-triangular
// form, and their product's last k_ - p columns W span P's orthogonal complement, so
// Z W (nv, k_ - p) is orthonormal and spans what is left.
void Law::remove_directions(int p) {
  const int k = k_, nv = static_cast<int>(Z_.rows());
  if (p <= 0) return;
  if (p >= k) {
    k_ = 0;
    z_identity_ = false;
    return;
  }
  small::householder_complement(P_.data(), nv, k, p, beta_.data(), W_.data(), nv);
  set_free(k - p);
}

// Z loses the row space of M (n x k_ rows of stride nv, rank n < k_), given L, the
// Cholesky factor of M M^T = L L^T (lower, n x n): Q = L^-1 M has orthonormal rows, the
// projector N = I - Q^T Q on their complement has rank q = k_ - n, and q steps of its
// pivoted Cholesky factorisation N = F F^T give F (k_ x q) with orthonormal columns
// (F F^T a projector of rank q: F = W R with W orthonormal and R R^T = I). About
// n^2 k / 2 + q n k products instead of the Householder reflections' n^2 (k - n / 3).
// False (nothing changed) when a pivot is not positive: rounding on a nearly singular M.
bool Law::remove_rows(const double* M, int n, const double* L, const int* lo, const int* hi) {
  const int k = k_, nv = static_cast<int>(Z_.rows()), q = k - n;
  double* a = tk_.data();  // a row of L, Q's column j, then W's row j
  int* qlo = span_.data();  // Q's row i is zero outside [qlo[i], qhi[i])
  int* qhi = qlo + nv;
  for (int i = 0; i < n && !q_ready_; ++i) {  // Q's row i at P_ + i * nv: L Q = M
    double* row = P_.data() + i * nv;
    std::copy(M + i * nv, M + i * nv + k, row);
    int f = i;  // L(i, c) = 0 for c < f (the rows of another branch)
    for (int c = 0; c < i; ++c) {
      a[c] = L[c * n + i];
      if (f == i && a[c] != 0.0) f = c;
    }
    int wl = lo[i], wh = hi[i];  // where the rows combined may not be zero
    for (int c = f; c < i; ++c) {
      wl = std::min(wl, qlo[c]);
      wh = std::max(wh, qhi[c]);
    }
    qlo[i] = wl;
    qhi[i] = wh;
    if (wl >= wh) continue;  // a zero row: L(i, i) > 0 leaves it zero
    small::sub_rows(a + f, P_.data() + f * nv + wl, nv, i - f, row + wl, wh - wl);
    small::scale(1.0 / L[i * n + i], row + wl, wh - wl);
  }
  double* d = beta_.data();  // N's diagonal, then what the steps leave of it
  std::fill(d, d + k, 1.0);
  for (int i = 0; i < n; ++i) {
    if (qlo[i] < qhi[i]) small::sub_squares(P_.data() + i * nv + qlo[i], d + qlo[i], qhi[i] - qlo[i]);
  }
  for (int s = 0; s < q; ++s) {
    const int j = static_cast<int>(std::max_element(d, d + k) - d);
    double* col = W_.data() + s * nv;  // N e_j less the steps before
    std::fill(col, col + k, 0.0);
    col[j] = 1.0;
    for (int i = 0; i < n; ++i) a[i] = P_(j, i);
    int r0 = 0, r1 = 0;
    small::nonzero_range(a, n, r0, r1);
    int wl = 0, wh = k;  // the Q rows' window, then the whole column for the W terms
    if (r0 < r1) {
      wl = j;
      wh = j + 1;
      for (int i = r0; i < r1; ++i) {
        wl = std::min(wl, qlo[i]);
        wh = std::max(wh, qhi[i]);
      }
      small::sub_rows(a + r0, P_.data() + r0 * nv + wl, nv, r1 - r0, col + wl, wh - wl);
    }
    for (int t = 0; t < s; ++t) a[t] = W_(j, t);
    small::sub_rows(a, W_.data(), nv, s, col, k);
    if (!(col[j] > 0.0)) return false;
    small::scale(1.0 / std::sqrt(col[j]), col, k);
    small::sub_squares(col, d, k);
    d[j] = -1.0;  // taken
  }
  set_free(q);
  return true;
}

// M = L Q by modified Gram-Schmidt on M's n rows (of k_, stride nv, row i zero outside
// [lo[i], hi[i])): Q's row i into P_ + i * nv, L (n x n, lower, column-major) into L.
// Each step runs where the rows may be nonzero (rows of different branches: L(i, c) = 0
// exactly, as in the Cholesky factorisation of M M^T). span_ keeps Q's rows' windows.
// False when a pivot is not positive (a row in the span of those before it).
bool Law::orthonormal_rows(const double* M, int n, const int* lo, const int* hi, double* L) {
  const int k = k_, nv = static_cast<int>(Z_.rows());
  int* qlo = span_.data();
  int* qhi = qlo + nv;
  for (int i = 0; i < n; ++i) {
    double* q = P_.data() + i * nv;
    int wl = lo[i], wh = hi[i];
    small::copy(M + i * nv, q, k);
    for (int c = 0; c < i; ++c) {
      const int from = std::max(wl, qlo[c]), to = std::min(wh, qhi[c]);
      double r = 0.0;
      if (from < to) r = small::dot(P_.data() + c * nv + from, q + from, to - from);
      L[c * n + i] = r;
      if (r == 0.0) continue;
      small::sub_scaled(r, P_.data() + c * nv + qlo[c], q + qlo[c], qhi[c] - qlo[c]);
      wl = std::min(wl, qlo[c]);
      wh = std::max(wh, qhi[c]);
    }
    const double norm = wl < wh ? std::sqrt(small::dot(q + wl, q + wl, wh - wl)) : 0.0;
    if (!(norm > 0.0)) return false;
    L[i * n + i] = norm;
    small::scale(1.0 / norm, q + wl, wh - wl);
    qlo[i] = wl;
    qhi[i] = wh;
  }
  return true;
}

}  // namespace clik
