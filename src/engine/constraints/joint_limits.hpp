// Joint-range constraints, eqs. (16)-(19) of docs/method.md (mirrors
// clik/constraints/joint_limits.py: evaluate, row, excursion, slack).
//
// The limits themselves (override, threshold cap at a quarter of the range,
// which joints are limited) are decided once by the Python JointLimits; this
// struct holds its result, read by ConstraintConfig's binding.
#pragma once

#include <string>
#include <vector>

#include "types.hpp"

namespace clik {

struct JointLimits {
  int n = 0;                             // limited joints
  std::vector<int> q_index;              // configuration index of each (evaluation)
  std::vector<int> v_index;              // velocity index of each (the row's entry)
  Vec lower, upper, threshold;           // per limited joint [rad or m]
  std::vector<std::string> joint_names;  // per limited joint
  std::vector<std::string> names;        // 2n rows: joint:<name>:lower ..., joint:<name>:upper ...
  Vec row_threshold;                     // d_q of each of the 2n rows
  Vec sign;                              // +1 (lower rows), -1 (upper rows)

  // Errors e_q = d_q - d (17) of all 2n rows into e (2n): lower rows d = q_i - lower,
  // upper rows d = upper - q_i; positive inside the threshold band.
  void evaluate(const Eigen::Ref<const Vec>& q, Eigen::Ref<Vec> e) const;

  // How far past its limit each row's joint is (2n): lower - q_i, q_i - upper.
  void excursion(const Eigen::Ref<const Vec>& q, Eigen::Ref<Vec> out) const;

  // Row u_q (19) of candidate row i into out (nv): +-1 at the joint's velocity index.
  void row(int i, Eigen::Ref<Eigen::RowVectorXd> out) const {
    out.setZero();
    out[v_index[i % n]] = sign[i];
  }
};

}  // namespace clik
