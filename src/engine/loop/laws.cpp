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
bool cholesky(const TaskMat& A, double shift, Factor& L) {
  const Eigen::Index n = A.rows();
  for (Eigen::Index j = 0; j < n; ++j) {
    double d = A(j, j) + shift;
    for (Eigen::Index k = 0; k < j; ++k) d -= L(j, k) * L(j, k);
    if (!(d > 0.0)) return false;
    L(j, j) = std::sqrt(d);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      double s = A(i, j);
      for (Eigen::Index k = 0; k < j; ++k) s -= L(i, k) * L(j, k);
      L(i, j) = s / L(j, j);
    }
  }
  return true;
}

// y <- (L L^T)^-1 y, by forward then backward substitution.
void cholesky_solve(const Factor& L, Eigen::Index n, double* y) {
  for (Eigen::Index i = 0; i < n; ++i) {
    double s = y[i];
    for (Eigen::Index k = 0; k < i; ++k) s -= L(i, k) * y[k];
    y[i] = s / L(i, i);
  }
  for (Eigen::Index i = n - 1; i >= 0; --i) {
    double s = y[i];
    for (Eigen::Index k = i + 1; k < n; ++k) s -= L(k, i) * y[k];
    y[i] = s / L(i, i);
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

Law::Level::Level(int n, int nv)
    : JN(n, nv), T(n, nv), A(n, n), S(n, n), H(nv, nv), Hs(nv, nv), rest(n), y(n), tmp(n),
      eig(n > MAX_EIGEN_ROWS ? n : 0), eig_small(n <= MAX_EIGEN_ROWS ? n : 0), llt(n), lltv(nv) {}

Law::Law(const LawSettings& settings, int rows, int nv, int m, const LevelPlan& plan)
    : Law(settings, rows, nv) {
  ends_ = plan.ends.empty() ? std::vector<int>{m} : plan.ends;
  zlevel_ = plan.objective_levels;
  by_levels_ = s_.kind == LawKind::pseudoinverse &&
               (ends_.size() > 1 || m > MAX_TASK_ROWS || !zlevel_.empty());
  if (!by_levels_) return;
  const int L = static_cast<int>(ends_.size());
  const int room = nv + m;  // B's rows: at most nv in exact arithmetic
  int start = 0;
  for (int l = 0; l < L; ++l) {
    const int n = ends_[l] - start;
    level_.emplace_back(n, nv);
    level_.back().T.resize(n, room);
    level_.back().basis = l + 1 < L;
    start = ends_[l];
  }
  for (int lz : zlevel_) level_[static_cast<size_t>(lz - 1)].basis = true;
  z_.assign(zlevel_.size(), Vec::Zero(nv));
  B_.setZero(room, nv);
  parts_.setZero(1 + L, nv);
  out_.setZero(nv);
  bz_.setZero(room);
  zp_.setZero(nv);
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

// -- by levels (clik/loop/levels.py's prioritized_levels, operation for operation) --------

namespace {

template <typename Rows>
double row_scale(const Rows& J) {
  return J.rows() ? std::sqrt(J.rowwise().squaredNorm().maxCoeff()) : 0.0;
}

// The step budget on a part (a row of parts_, or a vector).
template <typename V>
void budget(V&& qdot, double dt) {
  const double step = qdot.size() ? qdot.cwiseAbs().maxCoeff() * dt : 0.0;
  if (step > STEP_BUDGET) qdot *= STEP_BUDGET / step;
}

}  // namespace

// The constraint level on C = J[m:m+v] (v >= 1): parts_[0] = C^# b_c within the budget;
// B = C's right singular vectors above the rank tolerance (relative to level 1's scale).
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
      B_.row(0) = c / s;
      nb_ = 1;
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
  for (Eigen::Index i = 0; i < k; ++i) {
    if (sv[i] > keep) B_.row(nb_++) = Vm.col(i).transpose();
  }
}

double Law::prioritized_levels(const ExtendedTask& ext, int r, Eigen::Ref<Vec> qdot) {
  const int m = ext.m, v = r - m, nv = ext.nv;
  const int L = static_cast<int>(ends_.size());
  ext.demand(r, b_);
  bool finite = ext.J.topRows(r).allFinite() && b_.head(r).allFinite();
  for (const Vec& z : z_) finite = finite && z.allFinite();
  if (!finite) {
    qdot.setConstant(std::numeric_limits<double>::quiet_NaN());
    parts_.setConstant(std::numeric_limits<double>::quiet_NaN());
    qdot_c_ = parts_.row(0).transpose();
    return 0.0;
  }
  parts_.setZero();
  nb_ = 0;
  const int e1 = ends_[0];
  const double scale1 = row_scale(ext.J.topRows(e1));
  if (v > 0) level_constraints(ext, v, scale1);
  out_ = parts_.row(0).transpose();
  double blocked = 0.0;
  const double d2 = s_.damping * s_.damping;
  int start = 0;
  for (int l = 0; l < L; ++l) {
    Level& lv = level_[static_cast<size_t>(l)];
    const int n = ends_[l] - start;
    const auto Jl = ext.J.middleRows(start, n);
    const auto bl = b_.segment(start, n);
    const double scale = row_scale(Jl);
    const double epsilon = CONDITION_RATIO * scale, eps2 = epsilon * epsilon;
    // JN = J_l - (J_l B^T) B
    lv.JN = Jl;
    if (nb_ > 0) {
      const auto B = B_.topRows(nb_);
      lv.T.leftCols(nb_).noalias() = Jl * B.transpose();
      lv.JN.noalias() -= lv.T.leftCols(nb_) * B;
    }
    lv.rest = bl;
    lv.rest.noalias() -= Jl * out_;
    // JN JN^T, computed when a solve needs it (a level of more rows than the joints B
    // leaves free is singular for sure: solved in joint space without it)
    bool have_A = false;
    auto gram_A = [&] {
      if (!have_A) lv.A.noalias() = lv.JN * lv.JN.transpose();
      have_A = true;
    };
    const bool rank_short = n > nv - nb_;
    // y = V diag(1 / (max(w_i, eps^2) + lambda_0^2)) V^T rest (damped_solve)
    bool solved = false, based = false;
    const double keep = RANK_TOLERANCE * std::max(scale, 1.0);
    if (lv.basis) {
      gram_A();
      // Regular case: A - max(eps^2, tol^2) I positive definite, so no eigenvalue is
      // filtered and every direction is kept; with A = L L^T the rows L^-1 JN are an
      // orthonormal basis of JN's row space (L^-1 A L^-T = I): the same projector as
      // the eigenvectors' diag(1 / sqrt(w)) V^T JN, without an eigensolver.
      lv.S = lv.A;
      lv.S.diagonal().array() -= std::max(eps2, keep * keep);
      lv.llt.compute(lv.S);
      if (lv.llt.info() == Eigen::Success) {
        lv.S = lv.A;
        lv.llt.compute(lv.S);
        if (lv.llt.info() == Eigen::Success && nb_ + n <= B_.rows()) {
          auto rows = B_.middleRows(nb_, n);
          rows = lv.JN;
          lv.llt.matrixL().solveInPlace(rows);
          if (d2 > 0.0) {
            lv.S.diagonal().array() += d2;
            lv.llt.compute(lv.S);
          }
          if (lv.llt.info() == Eigen::Success) {
            lv.y = lv.rest;
            lv.llt.solveInPlace(lv.y);
            solved = based = true;
          }
        }
      }
    } else if (!rank_short) {  // regular case: two Cholesky factorisations, no eigensolver
      gram_A();
      lv.S = lv.A;
      lv.S.diagonal().array() -= eps2;
      lv.llt.compute(lv.S);
      if (lv.llt.info() == Eigen::Success) {
        lv.S = lv.A;
        lv.S.diagonal().array() += d2;
        lv.llt.compute(lv.S);
        if (lv.llt.info() == Eigen::Success) {
          lv.y = lv.rest;
          lv.llt.solveInPlace(lv.y);
          solved = true;
        }
      }
    }
    Eigen::Map<Vec> part(parts_.row(1 + l).data(), nv);
    bool direct = false;  // part written in joint space
    if (!solved && !lv.basis) {
      // JN JN^T singular (JN's rows in B's null space, or more rows than joints): in joint
      // space, JN^T f(JN JN^T) = f(JN^T JN) JN^T (f the filter of damped_solve, on the
      // nonzero eigenvalues; the zero ones give nothing either way). H = JN^T JN + c B^T B
      // lifts B's directions, which JN^T rest does not reach, to c >= eps^2; when H is
      // regular (every eigenvalue >= eps^2) part = (H + lambda_0^2 I)^-1 JN^T rest.
      const double c = std::max({scale * scale, eps2, 1.0});
      lv.H.noalias() = lv.JN.transpose() * lv.JN;
      if (nb_ > 0) lv.H.noalias() += c * (B_.topRows(nb_).transpose() * B_.topRows(nb_));
      lv.Hs = lv.H;
      lv.Hs.diagonal().array() -= eps2;
      lv.lltv.compute(lv.Hs);
      if (lv.lltv.info() == Eigen::Success) {
        lv.Hs = lv.H;
        lv.Hs.diagonal().array() += d2;
        lv.lltv.compute(lv.Hs);
        if (lv.lltv.info() == Eigen::Success) {
          part.noalias() = lv.JN.transpose() * lv.rest;
          lv.lltv.solveInPlace(part);
          solved = direct = true;
        }
      }
    }
    if (!solved) {  // the eigenpairs of JN JN^T (damping band, or a basis level not regular)
      gram_A();
      auto by_eigenpairs = [&](auto& eig) {
        eig.compute(lv.A);
        const auto& V = eig.eigenvectors();
        const auto& w = eig.eigenvalues();
        for (int i = 0; i < n; ++i) {
          const double wi = std::max(w[i], eps2) + d2;
          lv.tmp[i] = wi > 0.0 ? wi : std::numeric_limits<double>::infinity();
        }
        lv.y.noalias() = V.transpose() * lv.rest;
        lv.y.array() /= lv.tmp.array();
        lv.tmp.noalias() = V * lv.y;
        lv.y = lv.tmp;
        if (!lv.basis) return;
        // B gains JN's row space: diag(1 / sqrt(w)) V^T JN above the tolerance
        for (int i = 0; i < n; ++i) {
          if (w[i] > keep * keep && nb_ < B_.rows()) {
            B_.row(nb_).noalias() = V.col(i).transpose() * lv.JN;
            B_.row(nb_) /= std::sqrt(w[i]);
            ++nb_;
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
    }
    if (!direct) part.noalias() = lv.JN.transpose() * lv.y;
    if (l == 0 && !s_.budget_blocks) {  // measured on the law's own demand
      zp_ = out_ + part;
      blocked = unrealised_rows(ext, 0, e1, zp_);
    }
    budget(part, s_.dt);
    if (based) nb_ += n;  // the rows L^-1 JN written above
    for (size_t o = 0; o < zlevel_.size(); ++o) {  // N z = z - B^T B z, within the budget
      if (zlevel_[o] != l + 1) continue;
      zp_ = z_[o];
      if (nb_ > 0) {
        bz_.head(nb_).noalias() = B_.topRows(nb_) * z_[o];
        zp_.noalias() -= B_.topRows(nb_).transpose() * bz_.head(nb_);
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
  rest_.segment(a, b - a) = bt;
  rest_.segment(a, b - a).noalias() -= ext.J.middleRows(a, b - a) * x;
  return rest_.segment(a, b - a).norm() / demand;
}

}  // namespace clik
