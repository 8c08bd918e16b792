// The dexterity row (D1)-(D3): see dexterity.hpp and clik/constraints/dexterity.py.
#include "constraints/dexterity.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <pinocchio/algorithm/kinematics-derivatives.hpp>

#include "constraints/bind_kind.hpp"

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

namespace {

DexterityRow row_of(const KindSetup& setup) {
  if (setup.frame < 0 || static_cast<int>(setup.task_rows.size()) != setup.task_m) {
    throw std::invalid_argument("ConstraintRun: the dexterity row needs the task's frame and rows");
  }
  return DexterityRow(setup.model, setup.frame, setup.task_rows);
}

}  // namespace

Dexterity::Dexterity(const DexterityConfig& config, const KindSetup& setup)
    : cfg_(config), model_(setup.model), slot_(setup.slot), row_(row_of(setup)) {}

void Dexterity::names(std::vector<std::string>& out) {
  base_ = static_cast<int>(out.size());
  out.emplace_back("dexterity");
}

// DexterityRun.evaluate: the error (D2) of the task rows; a candidate when positive or active.
void Dexterity::evaluate(Sample& s, std::vector<Candidate>& out) {
  const double thr = cfg_.threshold;
  const double e = thr - row_.evaluate(s.ext.J.topRows(s.task_m));
  if (e > 0.0 || s.is_active[base_]) {
    Candidate c;
    c.key = base_;
    c.slot = slot_;
    c.item = 0;
    c.error = e;
    c.scale = c.threshold = thr;
    out.push_back(c);
  }
}

// DexterityRun.row: (D3).
void Dexterity::row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row) {
  row_.gradient(model_, s.data, row);
  c.feed = 0.0;
}

void DexterityConfig::bind(nanobind::module_& m) {
  bind_threshold_config<DexterityConfig>(m, "DexterityConfig",
                                         "The dexterity row (D1)-(D3): threshold w_min [m^p].");
}

}  // namespace clik
