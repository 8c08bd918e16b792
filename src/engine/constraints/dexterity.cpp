// The dexterity row (D1)-(D3): see dexterity.hpp and clik/constraints/dexterity.py.
#include "constraints/dexterity.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include <pinocchio/algorithm/kinematics-derivatives.hpp>

namespace clik {

DexterityRow::DexterityRow(const pinocchio::Model& model, int frame, std::vector<int> rows)
    : frame_(frame), m_(static_cast<int>(rows.size())), nv_(model.nv), rows_(std::move(rows)),
      J_(Mat::Zero(m_, model.nv)), A_(Mat::Zero(m_, model.nv)), G_(TaskMat::Zero(m_, m_)),
      llt_(MAX_TASK_ROWS), H_(6, model.nv, model.nv) {
  if (frame < 0 || frame >= static_cast<int>(model.nframes)) {
    throw std::invalid_argument("dexterity: the task's frame is not in the model");
  }
  if (m_ < 1 || m_ > MAX_TASK_ROWS) throw std::invalid_argument("dexterity: 1 to 6 task rows");
  for (int r : rows_) {
    if (r < 0 || r >= 6) throw std::invalid_argument("dexterity: task rows among 0..5");
  }
  H_.setZero();  // getFrameKinematicHessian writes the frame's supporting columns only
}

double DexterityRow::evaluate(const Eigen::Ref<const Mat>& J) {
  J_ = J;
  G_.noalias() = J_.lazyProduct(J_.transpose());
  llt_.compute(G_);
  regular_ = llt_.info() == Eigen::Success;
  w_ = regular_ ? llt_.matrixLLT().diagonal().prod() : 0.0;
  return w_;
}

void DexterityRow::gradient(const pinocchio::Model& model, pinocchio::Data& data,
                            Eigen::Ref<Eigen::RowVectorXd> out) {
  double scale = w_;
  if (!regular_) {  // singular: the damped measure's gradient
    const double mu = SINGULAR_DAMPING * std::max(G_.trace() / m_, 1e-300);
    G_.diagonal().array() += mu;
    llt_.compute(G_);
    scale = llt_.matrixLLT().diagonal().prod();
  }
  A_ = J_;
  llt_.solveInPlace(A_);  // (J J^T)^-1 J
  pinocchio::computeJointKinematicHessians(model, data);
  pinocchio::getFrameKinematicHessian(model, data, static_cast<pinocchio::FrameIndex>(frame_),
                                      pinocchio::LOCAL_WORLD_ALIGNED, H_);
  const double* H = H_.data();  // column-major: [a, i, k] at a + 6 i + 6 nv k
  for (int k = 0; k < nv_; ++k) {
    double sum = 0.0;
    for (int a = 0; a < m_; ++a) {
      const double* column = H + rows_[a] + 6 * static_cast<long>(nv_) * k;
      for (int i = 0; i < nv_; ++i) sum += A_(a, i) * column[6 * i];
    }
    out[k] = scale * sum;
  }
}

}  // namespace clik
