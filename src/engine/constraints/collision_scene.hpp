// The robot's link geometry and the obstacles in one Pinocchio GeometryModel
// (mirrors the per-sample parts of clik/constraints/collision_scene.py).
//
// The GeometryModel is the very one the Python CollisionScene built
// (ConstraintSet.scene.gmodel), borrowed, never copied or changed: links first,
// then obstacles; one collision pair per (link, obstacle), then the link-link
// pairs. Each run owns one CollisionScene (the core's, shared by the kinds that
// measure distances: obstacles and link pairs): its own GeometryData (coal's distance
// requests at GJK_TOLERANCE, as the Python side) and the joints' sphere centres.
// A moving obstacle's placement at time t is written into this GeometryData's
// oMg, not into the shared model.
#pragma once

#include <memory>
#include <string>
#include <cstdint>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/geometry.hpp>
#include <pinocchio/multibody/model.hpp>

#include "boundary.hpp"
#include "constraints/obstacle.hpp"
#include "types.hpp"

namespace clik {

// Tolerance of coal's GJK/EPA for link-obstacle and link-link distances [m]
// (collision_scene.GJK_TOLERANCE).
constexpr double GJK_TOLERANCE = 1e-9;

// What the Python CollisionScene decided once (`_engine.SceneConfig`, bound in
// bind_constraints.cpp).
struct SceneConfig {
  const pinocchio::GeometryModel* gmodel = nullptr;  // borrowed: links first, then obstacles
  std::shared_ptr<void> owner;   // keeps the pin.GeometryModel behind gmodel alive
  int n_links = 0;
  std::vector<int> link_joint;   // parent joint of each link geometry
  Vec local_radius;              // bounding radius of each link geometry about its joint [m]
  Eigen::MatrixXi obstacle_pairs;  // pair index of (link geometry i, obstacle o): (n_links, n_obs)
  struct SelfPair {
    int pair;  // collision pair index
    int a, b;  // link geometries
  };
  std::vector<SelfPair> self_pairs;
  std::vector<std::string> link_labels;  // per link geometry, in constraint names
  std::vector<int> joints;       // joints with link geometry (sorted): bounding-sphere centres
  Vec joint_radius;              // radius of each such joint's bounding sphere [m]
  std::vector<int> link_slot;    // index in `joints` of each link geometry's joint
  GeometryShape built;           // the GeometryModel's geometries and pairs when prepared

  // Sizes and indices within the GeometryModel; then joints, joint_radius and link_slot
  // from link_joint and local_radius (CollisionScene._bounding_spheres). Throws
  // std::invalid_argument.
  void prepare();

  // The link geometries' joints are the robot's.
  void check(const pinocchio::Model& model) const;

  int n_obstacles() const { return static_cast<int>(obstacle_pairs.cols()); }

  // Throws unless the GeometryModel still has the geometries and pairs it had when
  // prepared (a geometry or pair added or removed since would be read past its end).
  void require_unchanged() const {
    require(GeometryShape::of(*gmodel) == built,
            "SceneConfig: the pin.GeometryModel changed after the scene was built (geometries "
            "or collision pairs added or removed): build the ConstraintSet again");
  }
};

// rho (n_links, nv): |pdot| <= rho_i . |qdot| for any point of link geometry i
// (CollisionScene.motion_bounds): the chain of joint offsets from joint j to i's
// joint plus the geometry's radius; 1 for a prismatic joint; arm + 1 for a
// joint of more than one DOF; 0 for a joint that does not move link i.
Mat motion_bounds(const pinocchio::Model& model, const SceneConfig& scene);

// Signed distance of a pair, witness points (first on the link) and coal's normal.
struct PairDistance {
  double distance = 0.0;
  Vec3 point_a = Vec3::Zero();
  Vec3 point_b = Vec3::Zero();
  Vec3 normal = Vec3::Zero();
};

class CollisionScene {
 public:
  explicit CollisionScene(const SceneConfig& scene);

  // Place this obstacle (its geometry in the scene) at its pose at time t with the
  // geometries (a moving obstacle's kind registers it once).
  void move_with(const ObstacleConfig& obstacle);

  // Place this obstacle by its new pose and velocity from now on (a controller's move;
  // a static obstacle becomes one the scene places itself).
  void set_obstacle(const ObstacleConfig& obstacle);

  // A new sample: geometries are placed at data.oMi (a moving obstacle at time t [s])
  // when a distance first asks for them (`data` must outlive the sample's queries).
  void begin_sample(const pinocchio::Data& data, double t);

  // Joint origins (n_joints, 3) [m] from data.oMi: bounding-sphere centres.
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& place_joints(
      const pinocchio::Data& data);

  // Distance of collision pair `pair` at this sample's placements.
  void distance(int pair, PairDistance& out);

  // Geometry g's placement at this sample (a cloud's link query).
  const pinocchio::SE3& placement(int g) {
    place(static_cast<pinocchio::GeomIndex>(g));
    return gdata_.oMg[static_cast<std::size_t>(g)];
  }

  const SceneConfig& config() const { return *scene_; }

 private:
  const SceneConfig* scene_;
  // oMg of geometry g at this sample, as updateGeometryPlacements gives it (once per sample)
  void place(pinocchio::GeomIndex g);

  std::vector<ObstacleConfig> moving_;  // obstacles with a velocity
  std::vector<int> moving_of_;          // per geometry: its index in moving_, or -1
  pinocchio::GeometryData gdata_;
  const pinocchio::Data* data_ = nullptr;  // this sample's kinematics
  double t_ = 0.0;                         // this sample's time [s]
  std::uint64_t sample_ = 0;               // counts begin_sample()
  std::vector<std::uint64_t> placed_at_;   // per geometry: the sample it was placed at
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> joint_pos_;
};

}  // namespace clik
