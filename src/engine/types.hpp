// Shared numeric types of the engine: row-major like the numpy arrays they mirror.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <stdexcept>
#include <string>

namespace clik {

using Vec = Eigen::VectorXd;
using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

constexpr double INF = std::numeric_limits<double>::infinity();

// A run's sample times t_k [s]. An offline run reads them in place from the caller's array
// (a 10^8-sample run's grid is 800 MB: never copied; the array must outlive the run). An
// open run (a controller's ticks, no last sample) has no array: t_k = t0 + k dt, in this
// order of operations, as Python computes it (bit for bit), and n = LONG_MAX.
struct Clock {
  const double* t = nullptr;  // the grid (n), or null: an open run
  long n = 0;                 // samples (LONG_MAX: an open run)
  double t0 = 0.0, dt = 0.0;  // an open run's first time and step [s]

  static Clock grid(const double* t, long n) { return {t, n, 0.0, 0.0}; }
  static Clock open(double t0, double dt) {
    return {nullptr, std::numeric_limits<long>::max(), t0, dt};
  }

  bool is_open() const { return t == nullptr; }
  double operator[](long k) const {
    return t != nullptr ? t[k] : t0 + static_cast<double>(k) * dt;
  }
  long size() const { return n; }
};

// A task has at most six rows (x, y, z, rx, ry, rz): its square matrices live on the
// stack (fixed capacity, run-time size), faster than heap matrices at this size.
constexpr int MAX_TASK_ROWS = 6;
using TaskMat =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, MAX_TASK_ROWS, MAX_TASK_ROWS>;
using TaskVec = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, MAX_TASK_ROWS, 1>;

// The law, as clik/loop/laws.py names it.
enum class LawKind { transpose, nonlinear, pseudoinverse };

// The law named as in clik/loop/laws.py; std::invalid_argument for any other name.
inline LawKind law_kind(const std::string& law) {
  if (law == "pseudoinverse") return LawKind::pseudoinverse;
  if (law == "nonlinear") return LawKind::nonlinear;
  if (law == "transpose") return LawKind::transpose;
  throw std::invalid_argument("law: expected 'transpose', 'nonlinear' or 'pseudoinverse', got '" +
                              law + "'");
}

}  // namespace clik
