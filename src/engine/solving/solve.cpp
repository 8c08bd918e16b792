// Solve mode: see solving/solve.hpp and clik/solving/solve_problem.py (its specification).
#include "solving/solve.hpp"

#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace clik {

namespace {

// |v| summed in the order clik/solving/solve_problem.py's _norm3 sums it.
double norm3(const Eigen::Ref<const Vec3>& v) {
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

// Cutoff of numpy.linalg.pinv: singular values <= RCOND sigma_max are dropped.
constexpr double PINV_RCOND = 1e-15;

// pinocchio::log3(R, theta) without the cost of its theta ~ pi case: Pinocchio
// evaluates that case on every call, branch-free (three square roots, atan2 and
// norms: half of the function). Where cos(theta) >= -1 + prec this is the same
// arithmetic as log3_impl (src/spatial/log.hxx), so the same result; elsewhere,
// or for a rotation that is not finite, it is Pinocchio's own call.
Vec3 fast_log3(const Mat3& R, double& theta) {
  const double prec = pinocchio::TaylorSeriesExpansion<double>::precision<2>();
  const Mat3 Rnormed = pinocchio::renormalize_rotation_matrix(R);
  const double tr = Rnormed.trace();
  const double cos_value = (tr - 1.0) / 2.0;
  if (!(cos_value >= -1.0 + prec)) return pinocchio::log3(R, theta);
  const double eps = std::numeric_limits<double>::epsilon();
  const double acos_expansion = std::sqrt(2.0 * (1.0 - cos_value) + eps * eps);
  const double pi = pinocchio::PI<double>();
  theta = tr <= 3.0 - prec ? (tr >= -1.0 + prec ? std::acos(cos_value) : pi - acos_expansion)
                           : acos_expansion;
  Vec3 antisymmetric_R;
  pinocchio::unSkew(Rnormed, antisymmetric_R);
  const double n2 = antisymmetric_R.squaredNorm();
  const double t = theta >= prec ? theta / std::sin(theta) : 1.0 + n2 / 6.0 + n2 * n2 * 3.0 / 40.0;
  return t * antisymmetric_R;
}

Vec3 fast_log3(const Mat3& R) {
  double theta;
  return fast_log3(R, theta);
}

// e = log6(M) and Jlog = Jlog6(M^-1) for M = (R, p), as SolveProblem.error takes them
// from pinocchio.log6 and pinocchio.Jlog6, with the one log3 they share computed
// once (each of Pinocchio's functions computes its own: ~10 % of an iteration).
// The arithmetic is Pinocchio's (log6_impl and Jlog6_impl, src/spatial/log.hxx),
// with M^-1 = (R^T, -R^T p) and log3(R^T) = -log3(R) (fast_log3).
void log6_and_inverse_Jlog6(const pinocchio::SE3& M, Eigen::Matrix<double, 6, 1>& e,
                            Eigen::Matrix<double, 6, 6>& Jlog) {
  const Mat3& R = M.rotation();
  const Vec3& p = M.translation();
  const double prec2 = pinocchio::TaylorSeriesExpansion<double>::precision<2>();
  const double prec3 = pinocchio::TaylorSeriesExpansion<double>::precision<3>();

  // log6(M) (log6_impl)
  Vec3 antisymmetric_R;
  pinocchio::unSkew(R, antisymmetric_R);
  const double t2 = antisymmetric_R.squaredNorm();
  const double tr = R.trace();
  double theta;
  const Vec3 w = fast_log3(R, theta);  // theta in [0, pi]
  double st, ct;
  pinocchio::SINCOS(theta, &st, &ct);
  const bool small = tr >= 3.0 - prec2;
  const double alpha = small ? 1.0 - t2 / 12.0 - t2 * t2 / 720.0 : theta * st / (2.0 * (1.0 - ct));
  const double beta =
      small ? 1.0 / 12.0 + t2 / 720.0 : 1.0 / (theta * theta) - st / (2.0 * theta * (1.0 - ct));
  e.head<3>().noalias() = alpha * p - 0.5 * w.cross(p) + (beta * w.dot(p)) * w;
  e.tail<3>() = w;

  // Jlog6(M^-1) (Jlog6_impl): Jlog = [A, B; 0, A], B = C A
  const Vec3 w_inv = -w;
  const Vec3 p_inv = -(R.transpose() * p);
  auto A = Jlog.topLeftCorner<3, 3>();
  auto B = Jlog.topRightCorner<3, 3>();
  auto C = Jlog.bottomLeftCorner<3, 3>();
  pinocchio::Jlog3(theta, w_inv, A);
  Jlog.bottomRightCorner<3, 3>() = A;
  const double theta2 = theta * theta;
  const double tinv = 1.0 / theta, t2inv = tinv * tinv;
  const double inv_2_2ct = 1.0 / (2.0 * (1.0 - ct));
  const double beta6 = theta < prec3 ? 1.0 / 12.0 + theta2 / 720.0 : t2inv - st * tinv * inv_2_2ct;
  const double beta_dot_over_theta =
      theta < prec3 ? 1.0 / 360.0 : -2.0 * t2inv * t2inv + (1.0 + st * tinv) * t2inv * inv_2_2ct;
  const double wTp = w_inv.dot(p_inv);
  const Vec3 v3_tmp = (beta_dot_over_theta * wTp) * w_inv -
                      (theta2 * beta_dot_over_theta + 2.0 * beta6) * p_inv;
  C.noalias() = v3_tmp * w_inv.transpose();
  C.noalias() += beta6 * w_inv * p_inv.transpose();
  C.diagonal().array() += wTp * beta6;
  pinocchio::addSkew(0.5 * p_inv, C);
  B.noalias() = C * A;
  C.setZero();
}

}  // namespace

template <int Rows>
LawSystem<Rows>::LawSystem(int m, int nv)
    : J(m, nv),
      e(m),
      y_(m),
      tmp_(m),
      A_(m, m),
      L_(m, m),
      svd_(m, m, Eigen::ComputeFullU | Eigen::ComputeFullV) {}  // square: full = thin

template <int Rows>
void LawSystem<Rows>::qdot(LawKind law, double lambda2, Vec& dq) {
  if (law == LawKind::pseudoinverse) {
    // lazyProduct: a coefficient-wise product (Eigen's blocked GEMM packs its
    // operands first, ~3x the instructions at 6 x nv)
    A_.noalias() = J.lazyProduct(J.transpose());
    A_.diagonal().array() += lambda2;
    solve_small();
    dq.noalias() = J.transpose().lazyProduct(y_);
  } else {
    dq.noalias() = J.transpose() * e;
  }
}

// y_ = A_^-1 e by the Cholesky factor A_ = L L^T (unblocked, in L_: Eigen's LLT costs
// ~3x the instructions at 6 x 6), then forward and back substitution; false when a
// pivot is not > 0 or y_ is not finite.
template <int Rows>
bool LawSystem<Rows>::cholesky_solve() {
  const Eigen::Index m = A_.rows();
  for (Eigen::Index j = 0; j < m; ++j) {
    double d = A_(j, j);
    for (Eigen::Index k = 0; k < j; ++k) d -= L_(j, k) * L_(j, k);
    if (!(d > 0.0)) return false;
    L_(j, j) = std::sqrt(d);
    for (Eigen::Index i = j + 1; i < m; ++i) {
      double s = A_(i, j);
      for (Eigen::Index k = 0; k < j; ++k) s -= L_(i, k) * L_(j, k);
      L_(i, j) = s / L_(j, j);
    }
  }
  for (Eigen::Index i = 0; i < m; ++i) {
    double s = e[i];
    for (Eigen::Index k = 0; k < i; ++k) s -= L_(i, k) * y_[k];
    y_[i] = s / L_(i, i);
  }
  for (Eigen::Index i = m - 1; i >= 0; --i) {
    double s = y_[i];
    for (Eigen::Index k = i + 1; k < m; ++k) s -= L_(k, i) * y_[k];
    y_[i] = s / L_(i, i);
  }
  return std::isfinite(y_.dot(y_));
}

// y_ = A_^-1 e by Cholesky (A_ = J J^T + lambda^2 I is symmetric, and positive
// definite unless singular); else the SVD pseudoinverse (clik.loop.laws.solve_small).
template <int Rows>
void LawSystem<Rows>::solve_small() {
  if (cholesky_solve()) return;
  svd_.compute(A_, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const auto& sv = svd_.singularValues();
  const double cutoff = PINV_RCOND * (sv.size() ? sv.maxCoeff() : 0.0);
  tmp_.noalias() = svd_.matrixU().transpose() * e;
  for (Eigen::Index i = 0; i < sv.size(); ++i) tmp_[i] = sv[i] > cutoff ? tmp_[i] / sv[i] : 0.0;
  y_.noalias() = svd_.matrixV() * tmp_;
}

Solver::Solver(const pinocchio::Model& model, const SolveTask& task, const SolveSettings& settings,
               const Vec& reference)
    : model_(model),
      built_(ModelShape::of(model)),
      data_(model),
      task_(task),
      s_(settings),
      m_(static_cast<int>(task.rows.size())),
      reference_(reference),
      target_se3_(pinocchio::SE3::Identity()),
      lower_(model.nq),
      upper_(model.nq),
      q_(model.nq),
      q_next_(model.nq),
      dq_(model.nv),
      e6_(Eigen::Matrix<double, 6, 1>::Zero()),
      pose_(6, model.nv),
      masked_(m_ == 6 ? 0 : m_, model.nv),
      J6_(pinocchio::Data::Matrix6x::Zero(6, model.nv)),
      best_total_(std::numeric_limits<double>::infinity()),
      best_q_(model.nq),
      best_pos_(std::numeric_limits<double>::infinity()),
      best_rot_(std::numeric_limits<double>::infinity()) {
  if (m_ < 1 || m_ > 6) throw std::invalid_argument("rows: expected 1 to 6 task rows");
  require(finite_positive(s_.step) && finite_nonnegative(s_.damping) &&
              finite_nonnegative(s_.mu) && finite_positive(s_.tolerance) &&
              finite_positive(s_.orientation_tolerance) && s_.max_iterations >= 1,
          "Solver: step, tolerance and orientation_tolerance finite > 0, damping and mu finite "
          ">= 0, max_iterations >= 1");
  for (int r : task_.rows) {
    if (r < 0 || r > 5) throw std::invalid_argument("rows: expected indices in 0..5");
  }
  if (task_.frame_id >= model.frames.size()) throw std::invalid_argument("frame_id: no such frame");
  if (reference_.size() != model.nq) throw std::invalid_argument("reference: expected nq entries");
  full_pose_ = m_ == 6;
  has_position_ = std::any_of(task_.rows.begin(), task_.rows.end(), [](int r) { return r < 3; });
  has_orientation_ =
      std::any_of(task_.rows.begin(), task_.rows.end(), [](int r) { return r >= 3; });
  best_q_.setZero();
}

bool Solver::start(const Vec3& position, const Mat3& rotation, const Eigen::Ref<const Vec>& q0) {
  require_same_model(built_, model_, "Solver");
  if (q0.size() != model_.nq) throw std::invalid_argument("q0: expected nq entries");
  if (!position.allFinite() || !rotation.allFinite() || !q0.allFinite()) return false;
  position_ = position;
  rotation_ = rotation;
  target_se3_ = pinocchio::SE3(rotation, position);
  // Clipped: finite limits on both sides, and no joint with nq != nv (SolveProblem).
  const bool one_to_one = model_.nq == model_.nv;
  clip_ = false;
  for (Eigen::Index i = 0; i < model_.nq; ++i) {
    const double lo = model_.lowerPositionLimit[i], hi = model_.upperPositionLimit[i];
    const bool bounded = one_to_one && std::isfinite(lo) && std::isfinite(hi);
    lower_[i] = bounded ? lo : -std::numeric_limits<double>::infinity();
    upper_[i] = bounded ? hi : std::numeric_limits<double>::infinity();
    clip_ = clip_ || bounded;
  }
  success_ = false;
  iterations_ = attempts_ = 0;
  final_pos_ = final_rot_ = 0.0;
  best_total_ = best_pos_ = best_rot_ = std::numeric_limits<double>::infinity();
  q_ = q0;
  best_q_ = q_;  // reported if no attempt gives a finite error
  attempt_from_q();
  return true;
}

bool Solver::run(const Mat& starts) {
  require_same_model(built_, model_, "Solver");
  if (starts.cols() != model_.nq) throw std::invalid_argument("starts: expected nq columns");
  if (!starts.allFinite()) throw std::invalid_argument("starts: expected finite configurations");
  if (attempts_ == 0) throw std::logic_error("run: start() a solve first");
  for (Eigen::Index k = 0; k < starts.rows() && !success_; ++k) {
    q_ = starts.row(k).transpose();
    attempt_from_q();
  }
  return success_;
}

// One attempt from q_, counted into the solve (the loop body of solve()).
void Solver::attempt_from_q() {
  ++attempts_;
  const Attempt a = attempt();
  iterations_ += a.iterations;
  if (a.converged) {
    success_ = true;
    final_pos_ = a.position_error;
    final_rot_ = a.orientation_error;
  } else if (a.position_error + a.orientation_error < best_total_) {
    // keep the best attempt for a failure report
    best_total_ = a.position_error + a.orientation_error;
    best_q_ = q_;
    best_pos_ = a.position_error;
    best_rot_ = a.orientation_error;
  }
}

// Iterate from q_ until converged, stalled or out of iterations (SolveProblem.attempt).
Solver::Attempt Solver::attempt() {
  double best = std::numeric_limits<double>::infinity();
  int since_best = 0;
  double pos = std::numeric_limits<double>::infinity();
  double rot = pos;
  for (int iteration = 0; iteration < s_.max_iterations; ++iteration) {
    error(q_);
    pos = pos_;
    rot = rot_;
    if (pos <= s_.tolerance && rot <= s_.orientation_tolerance) {
      world_errors(pos, rot);
      return {true, iteration, pos, rot};
    }
    step(pos * pos + rot * rot);
    if (pos + rot < STALL_PROGRESS * best) {
      best = pos + rot;
      since_best = 0;
    } else if (++since_best >= STALL_ITERATIONS) {
      return {false, iteration + 1, pos, rot};
    }
  }
  return {false, s_.max_iterations, pos, rot};
}

// Task error e, its Jacobian J (in pose_ or masked_), and the position [m] and orientation [rad]
// norms pos_, rot_ at q (SolveProblem.error).
void Solver::error(const Vec& q) {
  const pinocchio::FrameIndex fid = task_.frame_id;
  if (full_pose_) {
    // e = log6(fMd), fMd = oMf^-1 oMd; the joints' Jacobians too (one pass: computing
    // them only when a step needs them, after forwardKinematics, measured 6 % more
    // instructions per solve), J = Jlog6(fMd^-1) J_local in pose_jacobian()
    pinocchio::computeJointJacobians(model_, data_, q);
    const pinocchio::SE3 fMd =
        pinocchio::updateFramePlacement(model_, data_, fid).actInv(target_se3_);
    log6_and_inverse_Jlog6(fMd, pose_.e, Jlog_);  // log6(fMd), Jlog6(fMd^-1)
    pos_ = norm3(pose_.e.head<3>());
    rot_ = norm3(pose_.e.tail<3>());
    return;
  }
  // Masked task: (6) e = (p_d - p, log3(R_d R^T)) and (3) J in LOCAL_WORLD_ALIGNED, on the rows.
  J6_.setZero();
  pinocchio::computeFrameJacobian(model_, data_, q, fid, pinocchio::LOCAL_WORLD_ALIGNED, J6_);
  const pinocchio::SE3& oMf = data_.oMf[fid];
  if (has_position_) e6_.head<3>() = position_ - oMf.translation();
  if (has_orientation_) {
    R_err_.noalias() = rotation_ * oMf.rotation().transpose();
    e6_.tail<3>() = fast_log3(R_err_);
  }
  for (int k = 0; k < m_; ++k) {
    masked_.e[k] = e6_[task_.rows[k]];
    masked_.J.row(k) = J6_.row(task_.rows[k]);
  }
  pos_ = norm3(e6_.head<3>());
  rot_ = norm3(e6_.tail<3>());
}

// J = Jlog6(fMd^-1) J_local at the last error()'s q (a full pose; SolveProblem.error),
// when a step needs it. J6_'s columns of joints that do not support the frame stay zero.
void Solver::pose_jacobian() {
  pinocchio::getFrameJacobian(model_, data_, task_.frame_id, pinocchio::LOCAL, J6_);
  pose_.J.noalias() = Jlog_.lazyProduct(J6_);  // (see LawSystem::qdot)
}

// Position and orientation error norms in the world frame at the last error()
// (SolveProblem.world_errors).
void Solver::world_errors(double& pos, double& rot) const {
  const pinocchio::SE3& oMf = data_.oMf[task_.frame_id];
  pos = 0.0;
  rot = 0.0;
  if (has_position_) pos = norm3(position_ - oMf.translation());
  if (has_orientation_) {
    const Mat3 R_err = rotation_ * oMf.rotation().transpose();
    rot = norm3(fast_log3(R_err));
  }
}

// One iteration, q <- q (+) step qdot, clipped into the joint limits (SolveProblem.step).
void Solver::step(double err2) {
  // (10): lambda^2 = lambda_0^2 + mu |e|^2 (Levenberg-Marquardt)
  const double lambda2 = s_.damping * s_.damping + s_.mu * err2;
  if (full_pose_) {
    pose_jacobian();
    pose_.qdot(s_.law, lambda2, dq_);
  } else {
    masked_.qdot(s_.law, lambda2, dq_);
  }
  dq_ *= s_.step;
  pinocchio::integrate(model_, q_, dq_, q_next_);
  q_.swap(q_next_);
  if (clip_) {
    for (Eigen::Index i = 0; i < q_.size(); ++i) {
      q_[i] = std::min(std::max(q_[i], lower_[i]), upper_[i]);  // NaN stays NaN
    }
  }
}

}  // namespace clik
