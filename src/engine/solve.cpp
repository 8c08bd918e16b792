// Solve mode: see solve.hpp and clik/solve_mode.py (its specification).
#include "solve.hpp"

#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace clik {

namespace {

// |v| summed in the order clik/solve_mode.py's _norm3 sums it.
double norm3(const Eigen::Ref<const Vec3>& v) {
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

// Cutoff of numpy.linalg.pinv: singular values <= RCOND sigma_max are dropped.
constexpr double PINV_RCOND = 1e-15;

}  // namespace

Solver::Solver(const pinocchio::Model& model, const SolveTask& task, const SolveSettings& settings)
    : model_(model),
      data_(model),
      task_(task),
      s_(settings),
      m_(static_cast<int>(task.rows.size())),
      target_se3_(pinocchio::SE3::Identity()),
      lower_(model.nq),
      upper_(model.nq),
      q_(model.nq),
      q_next_(model.nq),
      dq_(model.nv),
      e_(m_),
      y_(m_),
      e6_(Vec::Zero(6)),
      tmp_(m_),
      J_(m_, model.nv),
      A_(m_, m_),
      J6_(6, model.nv),
      ldlt_(m_),
      svd_(m_, m_, Eigen::ComputeThinU | Eigen::ComputeThinV),
      best_total_(std::numeric_limits<double>::infinity()),
      best_q_(model.nq),
      best_pos_(std::numeric_limits<double>::infinity()),
      best_rot_(std::numeric_limits<double>::infinity()) {
  if (m_ < 1 || m_ > 6) throw std::invalid_argument("rows: expected 1 to 6 task rows");
  for (int r : task_.rows) {
    if (r < 0 || r > 5) throw std::invalid_argument("rows: expected indices in 0..5");
  }
  if (task_.frame_id >= model.frames.size()) throw std::invalid_argument("frame_id: no such frame");
  full_pose_ = m_ == 6;
  has_position_ = std::any_of(task_.rows.begin(), task_.rows.end(), [](int r) { return r < 3; });
  has_orientation_ =
      std::any_of(task_.rows.begin(), task_.rows.end(), [](int r) { return r >= 3; });
  best_q_.setZero();
}

bool Solver::start(const Vec3& position, const Mat3& rotation, const Eigen::Ref<const Vec>& q0) {
  if (q0.size() != model_.nq) throw std::invalid_argument("q0: expected nq entries");
  if (!position.allFinite() || !rotation.allFinite() || !q0.allFinite()) return false;
  position_ = position;
  rotation_ = rotation;
  target_se3_ = pinocchio::SE3(rotation, position);
  // Clipped: finite limits on both sides, and no joint with nq != nv (_Problem).
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
  if (starts.cols() != model_.nq) throw std::invalid_argument("starts: expected nq columns");
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

// Iterate from q_ until converged, stalled or out of iterations (_Problem.attempt).
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

// Task error e_, its Jacobian J_, and the position [m] and orientation [rad]
// norms pos_, rot_ at q (_Problem.error).
void Solver::error(const Vec& q) {
  const pinocchio::FrameIndex fid = task_.frame_id;
  if (full_pose_) {
    // e = log6(fMd), fMd = oMf^-1 oMd; J = Jlog6(fMd^-1) J_local
    pinocchio::computeJointJacobians(model_, data_, q);
    const pinocchio::SE3 fMd = pinocchio::updateFramePlacement(model_, data_, fid).actInv(target_se3_);
    e_ = pinocchio::log6(fMd).toVector();
    pinocchio::Jlog6(fMd.inverse(), Jlog_);
    J6_.setZero();
    pinocchio::getFrameJacobian(model_, data_, fid, pinocchio::LOCAL, J6_);
    J_.noalias() = Jlog_ * J6_;
    pos_ = norm3(e_.head<3>());
    rot_ = norm3(e_.tail<3>());
    return;
  }
  // Masked task: (6) e = (p_d - p, log3(R_d R^T)) and (3) J in LOCAL_WORLD_ALIGNED, on the rows.
  J6_.setZero();
  pinocchio::computeFrameJacobian(model_, data_, q, fid, pinocchio::LOCAL_WORLD_ALIGNED, J6_);
  const pinocchio::SE3& oMf = data_.oMf[fid];
  if (has_position_) e6_.head<3>() = position_ - oMf.translation();
  if (has_orientation_) {
    R_err_.noalias() = rotation_ * oMf.rotation().transpose();
    e6_.tail<3>() = pinocchio::log3(R_err_);
  }
  for (int k = 0; k < m_; ++k) {
    e_[k] = e6_[task_.rows[k]];
    J_.row(k) = J6_.row(task_.rows[k]);
  }
  pos_ = norm3(e6_.head<3>());
  rot_ = norm3(e6_.tail<3>());
}

// Position and orientation error norms in the world frame at the last error() (_Problem.world_errors).
void Solver::world_errors(double& pos, double& rot) const {
  const pinocchio::SE3& oMf = data_.oMf[task_.frame_id];
  pos = 0.0;
  rot = 0.0;
  if (has_position_) pos = norm3(position_ - oMf.translation());
  if (has_orientation_) {
    const Mat3 R_err = rotation_ * oMf.rotation().transpose();
    rot = norm3(pinocchio::log3(R_err));
  }
}

// One iteration, q <- q (+) step qdot, clipped into the joint limits (_Problem.step).
void Solver::step(double err2) {
  if (s_.law == LawKind::pseudoinverse) {
    // (10) with lambda^2 = lambda_0^2 + mu |e|^2: qdot = J^T (J J^T + lambda^2 I)^-1 e
    A_.noalias() = J_ * J_.transpose();
    A_.diagonal().array() += s_.damping * s_.damping + s_.mu * err2;
    solve_small();
    dq_.noalias() = J_.transpose() * y_;
  } else {
    // (9): qdot = J^T e
    dq_.noalias() = J_.transpose() * e_;
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

// y_ = A_^-1 e_ by LDLT; where A_ is singular, the SVD pseudoinverse (clik.laws.solve_small).
void Solver::solve_small() {
  ldlt_.compute(A_);
  const bool singular =
      ldlt_.info() != Eigen::Success || (ldlt_.vectorD().array() == 0.0).any();
  if (!singular) {
    y_ = ldlt_.solve(e_);
    if (std::isfinite(y_.dot(y_))) return;
  }
  svd_.compute(A_, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd_.singularValues();
  const double cutoff = PINV_RCOND * (sv.size() ? sv.maxCoeff() : 0.0);
  tmp_.noalias() = svd_.matrixU().transpose() * e_;
  for (Eigen::Index i = 0; i < sv.size(); ++i) tmp_[i] = sv[i] > cutoff ? tmp_[i] / sv[i] : 0.0;
  y_.noalias() = svd_.matrixV() * tmp_;
}

}  // namespace clik
