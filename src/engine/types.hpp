// Shared numeric types of the engine: row-major like the numpy arrays they mirror.
#pragma once

#include <Eigen/Core>

namespace clik {

using Vec = Eigen::VectorXd;
using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// The law, as clik/laws.py names it.
enum class LawKind { transpose, nonlinear, pseudoinverse };

}  // namespace clik
