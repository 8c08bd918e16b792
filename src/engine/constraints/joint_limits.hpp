// Joint-range constraints, eqs. (16)-(19) of docs/method.md: a kind (see kind.hpp;
// mirrors clik/constraints/joint_limits.py).
//
// The limits themselves (override, threshold cap, which joints are limited) are decided
// once by the Python JointLimits; JointRangeConfig holds its result. Per sample, the
// rows' errors e_q = d_q - d (17) (lower rows d = q_i - lower, upper rows d = upper - q_i)
// are evaluated behind a certificate: the smallest margin to a threshold band, lowered by
// max |dq| per sample, says when a band may be entered; the rows are evaluated only then
// or while one of them is active. Row u_q (19): +-1 at the joint's velocity index.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "constraints/kind.hpp"
#include "types.hpp"

namespace clik {

class JointRange;

struct JointRangeConfig {
  using Run = JointRange;
  std::vector<int> q_index;              // configuration index of each limited joint
  std::vector<int> v_index;              // velocity index of each (the row's entry)
  Vec lower, upper, threshold;           // per limited joint [rad or m]
  std::vector<std::string> joint_names;  // per limited joint
  std::vector<std::string> names;        // 2n rows: joint:<name>:lower ..., joint:<name>:upper ...
  Vec row_threshold;                     // d_q of each of the 2n rows
  Vec sign;                              // +1 (lower rows), -1 (upper rows)
  std::optional<double> gain;            // [1/s]; none: the law's default

  int n() const { return static_cast<int>(q_index.size()); }
  void validate() const;  // sizes: n per joint, 2n per row (std::invalid_argument)
  bool wants_rows() const { return true; }
  void check(const pinocchio::Model& model, const SceneConfig* scene) const;
  static void bind(nanobind::module_& m);

  // Errors e_q (17) of all 2n rows into e (2n), positive inside the threshold band.
  void evaluate(const Eigen::Ref<const Vec>& q, Eigen::Ref<Vec> e) const;

  // Row u_q (19) of row i into out (nv).
  void row(int i, Eigen::Ref<Eigen::RowVectorXd> out) const {
    out.setZero();
    out[v_index[i % n()]] = sign[i];
  }
};

class JointRange : public KindDefaults {
 public:
  JointRange(const JointRangeConfig& config, const KindSetup& setup);
  void names(std::vector<std::string>& out);
  void evaluate(Sample& s, std::vector<Candidate>& out);
  void row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row);
  const std::optional<double>& gain() const { return cfg_.gain; }

 private:
  JointRangeConfig cfg_;
  int slot_, base_ = 0;
  Vec e_;                      // (2n) this sample's errors
  double joint_slack_ = -1.0;  // the certificate; unknown: evaluate at the first sample
};

}  // namespace clik
