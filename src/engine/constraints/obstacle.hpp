// An obstacle as a run sees it (mirrors clik/constraints/obstacle.py): a convex
// coal geometry attached to the world in the scene's GeometryModel, with a pose
// at t = 0 and a constant linear velocity. The geometry itself stays in the
// borrowed GeometryModel (built by the Python CollisionScene).
#pragma once

#include <string>

#include <pinocchio/spatial/se3.hpp>

#include "types.hpp"

namespace clik {

struct ObstacleConfig {
  std::string name;
  Mat3 rotation = Mat3::Identity();  // from rpy, as Obstacle.rotation
  Vec3 position = Vec3::Zero();      // centre at t = 0 [m]
  Vec3 velocity = Vec3::Zero();      // cdot of eq. (14) [m/s]
  double threshold = 0.0;            // d_o [m] (the obstacle's own, else the set's)
  int geometry = -1;                 // its index in the scene's GeometryModel (-1: from its pairs)

  bool moving() const { return (velocity.array() != 0.0).any(); }

  // Pose in the world at time t [s]: Obstacle.placement(t) (no rotation over time).
  pinocchio::SE3 placement(double t) const {
    return pinocchio::SE3(rotation, position + t * velocity);
  }
};

}  // namespace clik
