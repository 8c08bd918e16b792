// Law (10) by priority levels with eq. (5)'s objectives: see loop/laws.hpp and
// clik/loop/levels.py's prioritized_levels (the specification, mirrored operation for
// operation; the regular cases by Cholesky factorisations instead of eigenpairs).
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "loop/laws.hpp"

namespace clik {

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
  for (int lz : zlevel_) {
    if (lz < 1 || lz > L) throw std::invalid_argument("Law: an objective's level, 1 to L");
    level_[static_cast<size_t>(lz - 1)].basis = true;
  }
  z_.assign(zlevel_.size(), Vec::Zero(nv));
  B_.setZero(room, nv);
  parts_.setZero(1 + L, nv);
  out_.setZero(nv);
  bz_.setZero(room);
  zp_.setZero(nv);
}

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

// The products of this file are small (at most a few tens of rows and joints): lazy
// (coefficient-based) products, without the packing of Eigen's general matrix product.
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
      lv.T.leftCols(nb_).noalias() = Jl.lazyProduct(B.transpose());
      lv.JN.noalias() -= lv.T.leftCols(nb_).lazyProduct(B);
    }
    lv.rest = bl;
    lv.rest.noalias() -= Jl * out_;
    // JN JN^T, computed when a solve needs it (a level of more rows than the joints B
    // leaves free is singular for sure: solved in joint space without it)
    bool have_A = false;
    auto gram_A = [&] {
      if (!have_A) lv.A.noalias() = lv.JN.lazyProduct(lv.JN.transpose());
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
      lv.H.noalias() = lv.JN.transpose().lazyProduct(lv.JN);
      if (nb_ > 0) lv.H.noalias() += c * B_.topRows(nb_).transpose().lazyProduct(B_.topRows(nb_));
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
