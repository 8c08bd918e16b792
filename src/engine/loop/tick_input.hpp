// One tick's reference of the primary task, read from the caller's target (the
// controller's fast path, clik/control/controller.py; its Python form is
// clik/control/targets.py with task_reference and Controller._unmoved).
#pragma once

#include <cmath>

#include "loop/tracking.hpp"
#include "types.hpp"

namespace clik {

constexpr double ROTATION_TOLERANCE = 1e-6;  // max |R^T R - I| and |det R - 1| (Reference's)

class TickInput {
 public:
  explicit TickInput(const TaskConfig& task)
      : task_(task), ff_(TaskVec::Zero(static_cast<Eigen::Index>(task.rows.size()))) {
    R_.setIdentity();
  }

  // target: n = 16 (a 4x4 homogeneous pose, row-major, last row 0 0 0 1), 3 (a position: tasks without orientation rows)
  // or 9 (a rotation, row-major: tasks without position rows); velocity: vn = 6 (linear,
  // angular), 3 (tasks with one of the two) or 0 (none: zero feed-forward, at rest only
  // while the target stays where it was). False when the target or velocity does not fit
  // the task, a value is not finite, or R is not a rotation.
  bool set(const double* target, long n, const double* velocity, long vn) {
    const bool pos = task_.has_position, rot = task_.has_orientation;
    Vec3 p = p_;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R = R_;
    if (n == 16) {
      if (!(target[12] == 0.0 && target[13] == 0.0 && target[14] == 0.0 && target[15] == 1.0)) {
        return false;  // not a homogeneous pose (its last row 0 0 0 1)
      }
      for (int i = 0; i < 3; ++i) {
        p[i] = target[4 * i + 3];
        for (int j = 0; j < 3; ++j) R(i, j) = target[4 * i + j];
      }
    } else if (n == 3 && !rot) {
      p = Eigen::Map<const Vec3>(target);
    } else if (n == 9 && !pos) {
      R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(target);
    } else {
      return false;
    }
    if ((pos && !p.allFinite()) || (rot && !(R.allFinite() && is_rotation(R)))) return false;
    double v6[6] = {0, 0, 0, 0, 0, 0};
    if (vn == 6) {
      for (int i = 0; i < 6; ++i) v6[i] = velocity[i];
    } else if (vn == 3 && !(pos && rot)) {
      for (int i = 0; i < 3; ++i) v6[(pos ? 0 : 3) + i] = velocity[i];
    } else if (vn != 0) {
      return false;
    }
    bool zero = true;
    for (int i = 0; i < 6; ++i) {
      if (!std::isfinite(v6[i])) return false;
    }
    for (Eigen::Index i = 0; i < ff_.size(); ++i) {
      ff_[i] = v6[task_.rows[static_cast<size_t>(i)]];
      zero = zero && ff_[i] == 0.0;
    }
    const bool unmoved = started_ && (!pos || p == p_) && (!rot || R == R_);
    at_rest_ = zero && (vn != 0 || unmoved);
    p_ = p;
    R_ = R;
    started_ = true;
    return true;
  }

  const double* position() const { return task_.has_position ? p_.data() : nullptr; }
  const double* rotation() const { return task_.has_orientation ? R_.data() : nullptr; }
  const double* ff() const { return ff_.data(); }
  const bool* at_rest() const { return &at_rest_; }
  void forget() { started_ = false; }  // a tick given another way: "moved" next time

 private:
  static bool is_rotation(const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>& R) {
    const Mat3 G = R.transpose() * R - Mat3::Identity();
    return G.cwiseAbs().maxCoeff() <= ROTATION_TOLERANCE &&
           std::abs(R.determinant() - 1.0) <= ROTATION_TOLERANCE;
  }

  const TaskConfig& task_;
  Vec3 p_ = Vec3::Zero();
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R_;
  TaskVec ff_;
  bool at_rest_ = false, started_ = false;
};

}  // namespace clik
