// What a task takes as a controller's target: see tasks/targets.hpp and
// clik/control/targets.py (the specification: the same forms, checks and words).
#include "tasks/targets.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include <Eigen/LU>

#include "types.hpp"

namespace clik {

namespace {

bool all_finite(const double* v, long n) {
  for (long i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

bool is_rotation(const double* r) {
  const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(r);
  const Mat3 G = R.transpose() * R - Mat3::Identity();
  return G.cwiseAbs().maxCoeff() <= ROTATION_TOLERANCE &&
         std::abs(R.determinant() - 1.0) <= ROTATION_TOLERANCE;
}

bool refuse(Refusal& why, bool velocity, std::string expected, Refusal::Show show) {
  why = Refusal{velocity, std::move(expected), show};
  return false;
}

}  // namespace

// -- a frame's pose ---------------------------------------------------------------------

long FrameTarget::target_size(const Floats& f) const {
  if (f.is(4, 4)) return 16;
  if (f.is(3) && !rot) return 3;
  if (f.is(3, 3) && !pos) return 9;
  return -1;
}

long FrameTarget::velocity_size(const Floats& f) const {
  if (!f.given) return 0;
  if (f.is(6)) return 6;
  if (f.is(3) && !(pos && rot)) return 3;
  return -1;
}

std::string FrameTarget::target_forms() const {
  return std::string("a pin.SE3 or a 4x4 pose") + (rot ? "" : ", or a position (3,)") +
         (pos ? "" : ", or a rotation (3, 3)");
}

std::string FrameTarget::velocity_forms() const {
  return std::string("(linear, angular) (6,) [m/s, rad/s]") + (pos && rot ? "" : ", or (3,)");
}

bool FrameTarget::read(const Floats& target, const Floats& velocity, double* p, double* R,
                       double* ff, Refusal& why) const {
  const double* t = target.values.data();
  if (!all_finite(t, target_size(target))) {
    return refuse(why, false, "finite numbers", Refusal::Show::values);
  }
  double pt[3] = {0.0, 0.0, 0.0};
  double Rt[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  if (target.is(4, 4)) {
    if (!(t[12] == 0.0 && t[13] == 0.0 && t[14] == 0.0 && t[15] == 1.0)) {
      return refuse(why, false, "a 4x4 homogeneous pose (its last row 0 0 0 1)",
                    Refusal::Show::last_row);
    }
    for (int i = 0; i < 3; ++i) {
      pt[i] = t[4 * i + 3];
      for (int j = 0; j < 3; ++j) Rt[3 * i + j] = t[4 * i + j];
    }
  } else if (target.is(3)) {
    std::copy(t, t + 3, pt);
  } else {
    std::copy(t, t + 9, Rt);
  }
  if (rot && !is_rotation(Rt)) {
    return refuse(why, false, "a rotation (R^T R = I and det R = +1, within 1e-06)",
                  Refusal::Show::values);
  }
  double v6[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  const long vn = velocity_size(velocity);
  const double* v = velocity.values.data();
  if (!all_finite(v, vn)) return refuse(why, true, "finite numbers", Refusal::Show::values);
  if (vn == 6) {
    std::copy(v, v + 6, v6);
  } else if (vn == 3) {
    std::copy(v, v + 3, v6 + (pos ? 0 : 3));
  }
  if (p != nullptr) std::copy(pt, pt + 3, p);
  if (R != nullptr && rotation_ref) {
    if (rot) {
      std::copy(Rt, Rt + 9, R);
    } else {
      const double I[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
      std::copy(I, I + 9, R);
    }
  }
  for (std::size_t i = 0; i < rows.size(); ++i) ff[i] = v6[rows[i]];
  return true;
}

// -- values ----------------------------------------------------------------------------

std::string ValuesTarget::forms(const std::string& words, const std::string& in) const {
  if (m == 1) return "a " + words + " [" + in + "] (a number, or (1,))";
  return std::to_string(m) + " " + words + " (" + std::to_string(m) + ",) [" + in + "]";
}

bool ValuesTarget::read(const Floats& target, const Floats& velocity, double* ref, double* ff,
                        Refusal& why) const {
  const double* t = target.values.data();
  if (!all_finite(t, m)) return refuse(why, false, "finite numbers", Refusal::Show::values);
  const bool given = velocity_size(velocity) == m;
  const double* v = velocity.values.data();
  if (given && !all_finite(v, m)) {
    return refuse(why, true, "finite numbers", Refusal::Show::values);
  }
  std::copy(t, t + m, ref);
  if (given) {
    std::copy(v, v + m, ff);
  } else {
    std::fill(ff, ff + m, 0.0);
  }
  return true;
}

// -- any reader -------------------------------------------------------------------------

long largest_target(const TargetReader& reader) {
  return std::visit(
      [](const auto& r) -> long {
        if constexpr (std::is_same_v<std::decay_t<decltype(r)>, ValuesTarget>) return r.m;
        return 16;
      },
      reader);
}

long largest_velocity(const TargetReader& reader) {
  return std::visit(
      [](const auto& r) -> long {
        if constexpr (std::is_same_v<std::decay_t<decltype(r)>, ValuesTarget>) return r.m;
        return 6;
      },
      reader);
}

std::string target_forms(const TargetReader& reader) {
  return std::visit([](const auto& r) { return r.target_forms(); }, reader);
}

std::string velocity_forms(const TargetReader& reader) {
  return std::visit([](const auto& r) { return r.velocity_forms(); }, reader);
}

long target_size(const TargetReader& reader, const Floats& f) {
  return std::visit([&](const auto& r) { return r.target_size(f); }, reader);
}

long velocity_size(const TargetReader& reader, const Floats& f) {
  return std::visit([&](const auto& r) { return r.velocity_size(f); }, reader);
}

}  // namespace clik
