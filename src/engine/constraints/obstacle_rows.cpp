// Obstacle rows (13)-(15): see obstacle_rows.hpp and clik/constraints/obstacle_rows.py.
#include "constraints/obstacle_rows.hpp"

#include <cmath>

#include <pinocchio/algorithm/frames.hpp>

namespace clik {

RowTerms obstacle_row(ObstacleForm form, double threshold, double distance, const Vec3& p_link,
                      const Vec3& p_obstacle, const Vec3& normal,
                      const Eigen::Ref<const Eigen::Matrix<double, 3, Eigen::Dynamic>>& J_point,
                      const Vec3& obstacle_velocity, Eigen::Ref<Eigen::RowVectorXd> out) {
  const Vec3 d = p_link - p_obstacle;
  const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  Vec3 n;
  if (distance > CONTACT_DISTANCE && norm > MIN_WITNESS_GAP) {
    n = d / norm;
  } else {  // contact or penetration: push out along the contact normal
    n = -normal;
  }
  const double error = obstacle_error(form, threshold, distance).error;
  out.noalias() = n.transpose() * J_point;
  const double nv = n[0] * obstacle_velocity[0] + n[1] * obstacle_velocity[1] +
                    n[2] * obstacle_velocity[2];
  if (form == ObstacleForm::normalized) return {error, nv};
  const double scale = std::abs(distance);  // d(|d|^2 / 2) = |d| n^T dd (15)
  out *= scale;
  return {error, scale * nv};
}

void point_jacobian(const pinocchio::Model& model, pinocchio::Data& data, int joint,
                    const Vec3& point, pinocchio::Data::Matrix6x& J6) {
  // The point's placement in its joint frame (identity rotation), as the Python one.
  const pinocchio::SE3 local(Mat3::Identity(), data.oMi[joint].actInv(point));
  J6.setZero();  // getFrameJacobian writes only the joint's supporting columns
  pinocchio::getFrameJacobian(model, data, static_cast<pinocchio::JointIndex>(joint), local,
                              pinocchio::LOCAL_WORLD_ALIGNED, J6);
}

}  // namespace clik
