// The laws (8), (9), (10): see laws.hpp and clik/laws.py (their specification).
#include "laws.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace clik {

Law::ConstraintBlock::ConstraintBlock(int v, int nv)
    : C(v, nv), svd(v, nv, Eigen::ComputeThinU | Eigen::ComputeThinV) {}

Law::Law(const LawSettings& settings, int rows, int nv)
    : s_(settings), b_(rows), work_(rows), jte_(nv), qdot_c_(nv), qdot_t_(nv), rest_(rows),
      y_(rows), w_(rows), gain_(rows), tmp_(rows), JN_(rows, nv), A_(rows, rows),
      M_(rows, rows), eig_(rows), llt_(rows) {
  if (s_.kind != LawKind::pseudoinverse) return;
  constraint_.reserve(static_cast<size_t>(rows));
  for (int v = 1; v <= rows; ++v) constraint_.emplace_back(v, nv);
}

double Law::velocity(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot) {
  const auto J = ext.J.topRows(r);
  const auto e = ext.e.head(r);
  switch (s_.kind) {
    case LawKind::pseudoinverse:
      return prioritized(ext, r, qdot);
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

void Law::damped_solve(const Eigen::MatrixXd& A, const Vec& b, double epsilon, Vec& y) {
  // y = V diag(1 / (max(w_i, eps^2) + lambda_0^2)) V^T b, A = V diag(w) V^T
  const Eigen::Index n = A.rows();
  const double eps2 = epsilon * epsilon, d2 = s_.damping * s_.damping;
  // Regular case first: A - eps^2 I positive definite means no w_i is below eps^2,
  // and the filter is then exactly (A + lambda_0^2 I)^-1 (two small Cholesky
  // factorisations instead of an eigendecomposition).
  M_.resize(n, n);
  M_ = A;
  M_.diagonal().array() -= eps2;
  llt_.compute(M_);
  if (llt_.info() == Eigen::Success) {
    M_ = A;
    M_.diagonal().array() += d2;
    llt_.compute(M_);
    if (llt_.info() == Eigen::Success) {
      y.head(n) = b.head(n);
      llt_.solveInPlace(y.head(n));
      return;
    }
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

double Law::prioritized(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot) {
  const int m = ext.m;
  const int v = r - m;
  const auto J = ext.J.topRows(m);
  ext.demand(r, b_);
  const auto b_task = b_.head(m);
  const double scale = m ? std::sqrt(J.rowwise().squaredNorm().maxCoeff()) : 0.0;
  const double epsilon = CONDITION_RATIO * scale;
  const double d2 = s_.damping * s_.damping;
  if (v > 0) {
    // One SVD, C = U diag(s) V^T, for both levels: C's filtered inverse, and the
    // null-space projection J N = J - (J V_r) V_r^T on its row space V_r.
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
    // J N = J - J V_r V_r^T, V_r the right singular vectors of nonzero singular values
    JN_.resize(m, ext.nv);
    JN_ = J;
    const double keep = 1e-9 * std::max(scale, 1.0);
    for (Eigen::Index i = 0; i < k; ++i) {
      if (sv[i] > keep) {
        const auto vi = Vm.col(i);
        tmp_.head(m).noalias() = J * vi;
        JN_.noalias() -= tmp_.head(m) * vi.transpose();
      }
    }
    rest_.head(m) = b_task;
    rest_.head(m).noalias() -= J * qdot_c_;
    A_.resize(m, m);
    A_.noalias() = JN_ * JN_.transpose();
    damped_solve(A_, rest_, epsilon, y_);
    qdot_t_.noalias() = JN_.transpose() * y_.head(m);
    within_budget(qdot_t_);
    qdot = qdot_c_ + qdot_t_;
  } else {
    A_.resize(m, m);
    A_.noalias() = J * J.transpose();
    rest_.head(m) = b_task;
    damped_solve(A_, rest_, epsilon, y_);
    qdot_t_.noalias() = J.transpose() * y_.head(m);
    within_budget(qdot_t_);
    qdot = qdot_t_;
  }
  const double demand = b_task.norm();
  if (demand == 0.0) return 0.0;
  rest_.head(m) = b_task;
  rest_.head(m).noalias() -= J * qdot;
  return rest_.head(m).norm() / demand;
}

}  // namespace clik
