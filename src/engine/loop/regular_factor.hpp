// Factorisations law (10)'s levels share (loop/levels.cpp, loop/unit_level.cpp): the
// step budget, and a Gram matrix factorised when its eigenvalues clear the damping
// band's floor (the regular case).
#pragma once

#include <algorithm>
#include <limits>

#include "loop/laws.hpp"
#include "loop/small_dense.hpp"

namespace clik {

// The step budget on a part (a row of parts_, or a vector).
template <typename V>
inline void budget(V&& qdot, double dt) {
  const double step = qdot.size() ? qdot.cwiseAbs().maxCoeff() * dt : 0.0;
  if (step > STEP_BUDGET) qdot *= STEP_BUDGET / step;
}

// S = A + shift I (n x n lower triangles, leading dimensions lda, lds), factorised in
// place (S = L, L L^T): whether it is positive definite.
inline bool factor_shifted(const double* A, int lda, int n, double shift, double* S, int lds) {
  for (int j = 0; j < n; ++j) {
    std::copy(A + j * lda + j, A + j * lda + n, S + j * lds + j);
    S[j * lds + j] += shift;
  }
  return small::cholesky(S, lds, n);
}

// Whether L L^T - d2 I (L lower, n x n, from a factorisation of a matrix whose diagonal
// is at most top) shows every eigenvalue above the floor by small::eigen_lower_bound,
// less d2 and the factorisation's rounding, (n + 1) n eps top (Higham 2002, thm. 10.3).
// False is inconclusive. work holds 2 n.
inline bool bound_clears(const double* L, int ld, int n, double top, double floor, double d2,
                  double* work) {
  const double rounding = 2.0 * (n + 1) * n * std::numeric_limits<double>::epsilon() * top;
  return n > 4 && small::eigen_lower_bound(L, ld, n, work) - d2 - rounding > floor;
}

// S = the factor of A + d2 I (lower, S S^T) when A's eigenvalues are above the floor
// (and A + d2 I positive definite); false otherwise. The floor is shown cleared by the
// factor's own eigenvalue bound in the regular case; only when that bound is
// inconclusive is A - floor I factorised too (first, for n <= 4, where a factorisation
// costs less than the bound), into scratch when given (n x n, leading dimension lds),
// else into S, then A + d2 I again. work holds 2 n.
inline bool factor_regular(const double* A, int lda, int n, double floor, double d2, double* S,
                           int lds, double* work, double* scratch = nullptr) {
  if (n <= 4) {
    return factor_shifted(A, lda, n, -floor, S, lds) && factor_shifted(A, lda, n, d2, S, lds);
  }
  if (!factor_shifted(A, lda, n, d2, S, lds)) return false;
  double top = 0.0;
  for (int j = 0; j < n; ++j) top = std::max(top, A[j * lda + j] + d2);
  if (bound_clears(S, lds, n, top, floor, d2, work)) return true;
  if (scratch != nullptr) return factor_shifted(A, lda, n, -floor, scratch, lds);
  return factor_shifted(A, lda, n, -floor, S, lds) && factor_shifted(A, lda, n, d2, S, lds);
}

}  // namespace clik
