// The laws (8), (9), (10): see loop/laws.hpp and clik/loop/laws.py (their specification).
#include "loop/laws.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace clik {

namespace {

// A small lower-triangular factor (n <= MAX_TASK_ROWS), on the stack.
using Factor = Eigen::Matrix<double, MAX_TASK_ROWS, MAX_TASK_ROWS>;

// Cholesky factor L (lower triangle) of A + shift I, A symmetric n x n: false when a
// pivot is not positive (A + shift I is not positive definite). At this size plain
// loops beat a general factorisation's block bookkeeping.
template <int N>
bool cholesky_n(const TaskMat& A, double shift, Factor& L) {
  const double* a = A.data();  // column-major, N x N
  for (int j = 0; j < N; ++j) {
    double d = a[j * N + j] + shift;
    for (int k = 0; k < j; ++k) d -= L(j, k) * L(j, k);
    if (!(d > 0.0)) return false;
    L(j, j) = std::sqrt(d);
    for (int i = j + 1; i < N; ++i) {
      double s = a[j * N + i];
      for (int k = 0; k < j; ++k) s -= L(i, k) * L(j, k);
      L(i, j) = s / L(j, j);
    }
  }
  return true;
}

// (the size a template argument, so the loops unroll: ~half the instructions of loops
// over a run-time size at 6 x 6, the same arithmetic in the same order)
bool cholesky(const TaskMat& A, double shift, Factor& L) {
  static_assert(MAX_TASK_ROWS == 6, "cholesky: one case per size");
  switch (A.rows()) {
    case 1: return cholesky_n<1>(A, shift, L);
    case 2: return cholesky_n<2>(A, shift, L);
    case 3: return cholesky_n<3>(A, shift, L);
    case 4: return cholesky_n<4>(A, shift, L);
    case 5: return cholesky_n<5>(A, shift, L);
    case 6: return cholesky_n<6>(A, shift, L);
    default: return true;  // 0 x 0
  }
}

template <int N>
void cholesky_solve_n(const Factor& L, double* y) {
  for (int i = 0; i < N; ++i) {
    double s = y[i];
    for (int k = 0; k < i; ++k) s -= L(i, k) * y[k];
    y[i] = s / L(i, i);
  }
  for (int i = N - 1; i >= 0; --i) {
    double s = y[i];
    for (int k = i + 1; k < N; ++k) s -= L(k, i) * y[k];
    y[i] = s / L(i, i);
  }
}

// y <- (L L^T)^-1 y, by forward then backward substitution.
void cholesky_solve(const Factor& L, Eigen::Index n, double* y) {
  switch (n) {
    case 1: return cholesky_solve_n<1>(L, y);
    case 2: return cholesky_solve_n<2>(L, y);
    case 3: return cholesky_solve_n<3>(L, y);
    case 4: return cholesky_solve_n<4>(L, y);
    case 5: return cholesky_solve_n<5>(L, y);
    case 6: return cholesky_solve_n<6>(L, y);
    default: return;
  }
}

// A = B B^T for B with n <= MAX_TASK_ROWS rows (the lower triangle, mirrored).
template <typename Rows>
void gram(const Rows& B, TaskMat& A) {
  const Eigen::Index n = B.rows();
  A.resize(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j <= i; ++j) A(i, j) = A(j, i) = B.row(i).dot(B.row(j));
  }
}

}  // namespace

Law::ConstraintBlock::ConstraintBlock(int v, int nv)
    : C(v, nv), svd(v, nv, Eigen::ComputeThinU | Eigen::ComputeThinV) {}

Law::Law(const LawSettings& settings, int rows, int nv)
    : s_(settings), b_(rows), work_(rows), jte_(nv), qdot_c_(nv), qdot_t_(nv), rest_(rows),
      y_(rows), w_(rows), gain_(rows), tmp_(rows), JN_(rows, nv), A_(MAX_TASK_ROWS, MAX_TASK_ROWS),
      eig_(MAX_TASK_ROWS) {
  if (s_.kind != LawKind::pseudoinverse) return;
  constraint_.reserve(static_cast<size_t>(rows));
  for (int v = 1; v <= rows; ++v) constraint_.emplace_back(v, nv);
}

double Law::velocity(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot) {
  const auto J = ext.J.topRows(r);
  const auto e = ext.e.head(r);
  switch (s_.kind) {
    case LawKind::pseudoinverse:
      return by_levels_ ? prioritized_levels(ext, r, qdot) : prioritized(ext, r, qdot);
    case LawKind::transpose: {  // (9): qdot = J^T K e
      work_.head(r) = ext.K.head(r).cwiseProduct(e);
      qdot.noalias() = J.transpose() * work_.head(r);
      return 0.0;
    }
    case LawKind::nonlinear: {  // (8): qdot = J^T K e + beta J^T e, |beta| <= beta_max
      jte_.noalias() = J.transpose() * e;
      const double den = jte_.dot(jte_);
      const double num = e.dot(ext.ff.head(r));
      double beta = den > 0.0 ? num / den : 0.0;
      beta = std::clamp(beta, -s_.beta_max, s_.beta_max);
      work_.head(r) = ext.K.head(r).cwiseProduct(e);
      qdot.noalias() = J.transpose() * work_.head(r);
      qdot += beta * jte_;
      return 0.0;
    }
  }
  return 0.0;
}

void Law::damped_solve(const TaskMat& A, const Vec& b, double epsilon, Vec& y) {
  // y = V diag(1 / (max(w_i, eps^2) + lambda_0^2)) V^T b, A = V diag(w) V^T
  const Eigen::Index n = A.rows();
  const double eps2 = epsilon * epsilon, d2 = s_.damping * s_.damping;
  // Regular case first: A - eps^2 I positive definite means no w_i is below eps^2,
  // and the filter is then exactly (A + lambda_0^2 I)^-1 (two small Cholesky
  // factorisations instead of an eigendecomposition).
  Factor L;
  if (cholesky(A, -eps2, L) && cholesky(A, d2, L)) {
    y.head(n) = b.head(n);
    cholesky_solve(L, n, y.data());
    return;
  }
  eig_.compute(A);
  const auto& V = eig_.eigenvectors();
  Vec& w = w_;
  w.head(n) = eig_.eigenvalues();
  for (Eigen::Index i = 0; i < n; ++i) {
    double wi = std::max(w[i], eps2) + d2;
    w[i] = wi > 0.0 ? wi : std::numeric_limits<double>::infinity();
  }
  tmp_.head(n).noalias() = V.transpose() * b.head(n);
  tmp_.head(n).array() /= w.head(n).array();
  y.head(n).noalias() = V * tmp_.head(n);
}

void Law::within_budget(Vec& qdot) const {
  const double step = qdot.size() ? qdot.cwiseAbs().maxCoeff() * s_.dt : 0.0;
  if (step > STEP_BUDGET) qdot *= STEP_BUDGET / step;
}

// Level 1 of law (10) on the v active constraint rows C = J[m:m+v] (v >= 1): the
// filtered inverse qdot_c = C^+ b_c within the step budget, and the task's Jacobian
// projected onto C's null space, J N = J - (J V_r) V_r^T, V_r the right singular
// vectors of C's nonzero singular values. One SVD, C = U diag(s) V^T, serves both.
void Law::constraint_level(const ExtendedTask& ext, int v, double epsilon) {
  const int m = ext.m;
  if (v == 1) return one_constraint_level(ext, epsilon);
  const double d2 = s_.damping * s_.damping;
  const auto J = ext.J.topRows(m);
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
  qdot_c_.noalias() = Vm * tmp_.head(k);
  within_budget(qdot_c_);
  JN_ = J;
  const double keep = RANK_TOLERANCE * std::max(scale_, 1.0);
  for (Eigen::Index i = 0; i < k; ++i) {
    if (sv[i] > keep) {
      const auto vi = Vm.col(i);
      tmp_.head(m).noalias() = J * vi;
      JN_.noalias() -= tmp_.head(m) * vi.transpose();
    }
  }
}

// constraint_level for one row c^T: its SVD is s = |c|, U = 1, V = c / s.
void Law::one_constraint_level(const ExtendedTask& ext, double epsilon) {
  const int m = ext.m;
  const double d2 = s_.damping * s_.damping;
  const auto J = ext.J.topRows(m);
  const auto c = ext.J.row(m);
  const double s = c.norm();
  JN_ = J;
  if (s == 0.0) {  // no direction: the level asks nothing, projects nothing
    qdot_c_.setZero();
    return;
  }
  const double gain = s / (std::max(s * s, epsilon * epsilon) + d2);
  qdot_c_.noalias() = (gain * b_[m] / s) * c.transpose();
  within_budget(qdot_c_);
  if (s > RANK_TOLERANCE * std::max(scale_, 1.0)) {
    tmp_.head(m).noalias() = J * c.transpose();
    JN_.noalias() -= (tmp_.head(m) / (s * s)) * c;
  }
}

double Law::prioritized(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot) {
  const int m = ext.m;
  const int v = r - m;
  const auto J = ext.J.topRows(m);
  ext.demand(r, b_);
  const auto b_task = b_.head(m);
  scale_ = std::sqrt(J.rowwise().squaredNorm().maxCoeff());
  const double epsilon = CONDITION_RATIO * scale_;
  if (v > 0) {
    constraint_level(ext, v, epsilon);
    // Level 2: the task, in C's null space, on what level 1 left of its demand.
    rest_.head(m) = b_task;
    rest_.head(m).noalias() -= J * qdot_c_;
    gram(JN_, A_);
    damped_solve(A_, rest_, epsilon, y_);
    qdot_t_.noalias() = JN_.transpose() * y_.head(m);
  } else {
    qdot_c_.setZero();
    gram(J, A_);
    rest_.head(m) = b_task;
    damped_solve(A_, rest_, epsilon, y_);
    qdot_t_.noalias() = J.transpose() * y_.head(m);
  }
  if (s_.budget_blocks) {
    within_budget(qdot_t_);
    qdot = qdot_c_ + qdot_t_;
    return unrealised(ext, qdot);
  }
  qdot = qdot_c_ + qdot_t_;
  const double blocked = unrealised(ext, qdot);
  within_budget(qdot_t_);
  qdot = qdot_c_ + qdot_t_;
  return blocked;
}

// |b - J qdot| / |b| on the task rows (b_ holds the demand): 0 when realised exactly.
double Law::unrealised(const ExtendedTask& ext, const Eigen::Ref<const Vec>& qdot) {
  const int m = ext.m;
  const auto b_task = b_.head(m);
  const double demand = b_task.norm();
  if (demand == 0.0) return 0.0;
  rest_.head(m) = b_task;
  rest_.head(m).noalias() -= ext.J.topRows(m) * qdot;
  return rest_.head(m).norm() / demand;
}

}  // namespace clik
