// The dexterity row, (D1)-(D3) of docs/method.md, "Dexterity" (mirrors
// clik/constraints/dexterity.py and clik/tasks/manipulability.py).
//
// With J the task Jacobian (m, nv): the frame's LOCAL_WORLD_ALIGNED Jacobian
// masked to the task's rows, the very rows 0..m of the extended task:
// - w = sqrt(det(J J^T)) (D1), from the Cholesky factor L of J J^T as prod(diag(L)),
//   0 when J J^T is not positive definite;
// - error e_w = w_min - w (D2), positive below the threshold;
// - row j_w = grad_q w (D3): dw/dq_k = w sum_ij [(J J^T)^-1 J]_ij dJ_ij/dq_k, with
//   dJ/dq from Pinocchio's kinematic Hessian of the task frame (world-aligned, the
//   frame's placement on its joint included). At a singular J J^T the row is the
//   gradient of sqrt(det(J J^T + mu I)), mu = SINGULAR_DAMPING times the mean eigenvalue.
//
// DexterityRow is a run's workspace, allocated once: evaluate() each sample (an m x m
// Cholesky factor), gradient() only while the row is active (the Hessian). Dexterity is
// the kind (see kind.hpp): one row, key "dexterity", item 0.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "constraints/kind.hpp"
#include "types.hpp"

namespace clik {

// mu of the row at a singular J J^T, relative to its mean eigenvalue.
constexpr double SINGULAR_DAMPING = 1e-9;

class Dexterity;

struct DexterityConfig {
  using Run = Dexterity;
  double threshold = 0.0;      // w_min [m^p, p the task's position rows]
  std::optional<double> gain;  // [1/s]; none: the law's default

  bool wants_rows() const { return true; }
  void check(const pinocchio::Model&, const SceneConfig*) const {}
  static void bind(nanobind::module_& m);
};

class DexterityRow {
 public:
  // frame: the task's frame; rows: its rows among (x, y, z, rx, ry, rz).
  DexterityRow(const pinocchio::Model& model, int frame, std::vector<int> rows);

  // w (D1) of the task rows J (m, nv); keeps J and its factor for gradient().
  double evaluate(const Eigen::Ref<const Mat>& J);

  // j_w = grad_q w (D3) into out (nv), at the J of the last evaluate(). data: joint
  // Jacobians at that configuration (computeJointJacobians); its kinematic Hessians
  // are computed here.
  void gradient(const pinocchio::Model& model, pinocchio::Data& data,
                Eigen::Ref<Eigen::RowVectorXd> out);

 private:
  int frame_, m_, nv_;
  std::vector<int> rows_;
  Mat J_, A_;     // (m, nv): the task rows; (J J^T)^-1 J
  TaskMat G_;     // J J^T (m, m)
  Eigen::LLT<TaskMat> llt_;
  bool regular_ = false;  // J J^T positive definite (else the damped factor)
  double w_ = 0.0;
  pinocchio::Data::Tensor3x H_;  // (6, nv, nv): [a, i, k] = dJ_ai / dq_k, column-major
};

class Dexterity : public KindDefaults {
 public:
  // Throws std::invalid_argument without the task's frame and rows.
  Dexterity(const DexterityConfig& config, const KindSetup& setup);
  void names(std::vector<std::string>& out);
  void evaluate(Sample& s, std::vector<Candidate>& out);
  void row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row);
  const std::optional<double>& gain() const { return cfg_.gain; }

 private:
  DexterityConfig cfg_;
  const pinocchio::Model& model_;
  int slot_, base_ = 0;
  DexterityRow row_;
};

}  // namespace clik
