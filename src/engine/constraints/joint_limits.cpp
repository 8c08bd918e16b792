// Joint-range errors (17): see joint_limits.hpp and clik/constraints/joint_limits.py.
#include "constraints/joint_limits.hpp"

namespace clik {

void JointLimits::evaluate(const Eigen::Ref<const Vec>& q, Eigen::Ref<Vec> e) const {
  // The same operations as the numpy version: e = thr - d, d = q - lower or
  // -(q + (-upper)) = upper - q (both exact rewrites in IEEE arithmetic).
  for (int i = 0; i < n; ++i) {
    const double qi = q[q_index[i]];
    e[i] = row_threshold[i] - (qi - lower[i]);
    e[n + i] = row_threshold[n + i] - (upper[i] - qi);
  }
}

void JointLimits::excursion(const Eigen::Ref<const Vec>& q, Eigen::Ref<Vec> out) const {
  for (int i = 0; i < n; ++i) {
    const double qi = q[q_index[i]];
    out[i] = lower[i] - qi;
    out[n + i] = qi - upper[i];
  }
}

}  // namespace clik
