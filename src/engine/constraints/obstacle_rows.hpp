// Obstacle rows, eqs. (13)-(15) of docs/method.md, from coal's witness points
// (mirrors clik/constraints/obstacle_rows.py); the obstacle kind's rows, and the
// link pairs' with the second link in the obstacle's place.
//
// With p_o the link's witness point, c the obstacle's, d = p_o - c, threshold d_o:
// - squared (the paper's): e_o = 1/2 (d_o^2 - s|s|) (13), row |s| n^T J_po (15),
//   feed-forward |s| n^T cdot (14);
// - normalized: e_o = d_o - s, row n^T J_po, feed-forward n^T cdot,
// with n = d / |d| (coal's contact normal, negated, in contact or penetration)
// and s the signed distance.
#pragma once

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "types.hpp"

namespace clik {

// At or below this distance [m] the row's direction is coal's contact normal; witness
// points closer than MIN_WITNESS_GAP [m] give no direction of their own.
constexpr double CONTACT_DISTANCE = 1e-9;
constexpr double MIN_WITNESS_GAP = 1e-12;

enum class ObstacleForm { normalized, squared };

struct ErrorScale {
  double error;  // e_o, positive inside the threshold [m or m^2]
  double scale;  // d_o or d_o^2 / 2: the error's unit scale (hysteresis, activation order)
};

// Error e_o of a link at signed distance s [m] from an obstacle, and its scale.
inline ErrorScale obstacle_error(ObstacleForm form, double threshold, double distance) {
  if (form == ObstacleForm::normalized) return {threshold - distance, threshold};
  return {0.5 * (threshold * threshold - distance * std::abs(distance)),
          0.5 * threshold * threshold};
}

struct RowTerms {
  double error;  // e_o
  double feed;   // feed-forward (14)
};

// Fill the row j_o (nv) into out; return e_o and the feed-forward.
// J_point: linear Jacobian (3, nv) of p_link; obstacle_velocity: cdot [m/s].
RowTerms obstacle_row(ObstacleForm form, double threshold, double distance, const Vec3& p_link,
                      const Vec3& p_obstacle, const Vec3& normal,
                      const Eigen::Ref<const Eigen::Matrix<double, 3, Eigen::Dynamic>>& J_point,
                      const Vec3& obstacle_velocity, Eigen::Ref<Eigen::RowVectorXd> out);

// Jacobian (6, nv) of a point fixed on joint `joint`'s body, LOCAL_WORLD_ALIGNED, into J6
// (its top 3 rows are the point's linear Jacobian). Needs computeJointJacobians at q.
void point_jacobian(const pinocchio::Model& model, pinocchio::Data& data, int joint,
                    const Vec3& point, pinocchio::Data::Matrix6x& J6);

}  // namespace clik
