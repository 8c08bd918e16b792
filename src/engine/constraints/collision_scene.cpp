// Per-sample collision queries: see collision_scene.hpp and
// clik/constraints/collision_scene.py. The only translation unit of the
// constraints that includes Pinocchio's collision algorithms (coal).
#include "constraints/collision_scene.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <pinocchio/algorithm/geometry.hpp>
#include <pinocchio/collision/distance.hpp>

namespace clik {

namespace {

void scene_require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("SceneConfig: " + what);
}

}  // namespace

void SceneConfig::prepare() {
  scene_require(gmodel != nullptr, "no GeometryModel");
  const int n_geoms = static_cast<int>(gmodel->ngeoms);
  const int n_pairs = static_cast<int>(gmodel->collisionPairs.size());
  scene_require(n_links >= 0 && n_links <= n_geoms,
          "n_links = " + std::to_string(n_links) + " but the GeometryModel has " +
              std::to_string(n_geoms) + " geometries");
  const auto n = static_cast<std::size_t>(n_links);
  scene_require(link_joint.size() == n && static_cast<std::size_t>(local_radius.size()) == n &&
              link_labels.size() == n && obstacle_pairs.rows() == n_links,
          "link_joint, local_radius, link_labels and obstacle_pairs need one entry (row) per "
          "link geometry (n_links = " + std::to_string(n_links) + ")");
  for (int i = 0; i < obstacle_pairs.size(); ++i) {
    const int p = obstacle_pairs.data()[i];
    scene_require(p >= 0 && p < n_pairs, "obstacle_pairs: pair " + std::to_string(p) +
                                       " not among the GeometryModel's " +
                                       std::to_string(n_pairs) + " collision pairs");
  }
  for (const SelfPair& sp : self_pairs) {
    scene_require(sp.pair >= 0 && sp.pair < n_pairs && sp.a >= 0 && sp.a < n_links && sp.b >= 0 &&
                sp.b < n_links,
            "self_pairs: (pair, a, b) = (" + std::to_string(sp.pair) + ", " +
                std::to_string(sp.a) + ", " + std::to_string(sp.b) +
                ") not a collision pair of two link geometries");
  }
  for (int i = 0; i < n_links; ++i) {
    scene_require(finite_nonnegative(local_radius[i]),
                  "local_radius: finite radii >= 0 [m], one per link geometry");
  }
  built = GeometryShape::of(*gmodel);
  joints.assign(link_joint.begin(), link_joint.end());
  std::sort(joints.begin(), joints.end());
  joints.erase(std::unique(joints.begin(), joints.end()), joints.end());
  joint_radius = Vec::Constant(static_cast<Eigen::Index>(joints.size()), -INFINITY);
  link_slot.assign(link_joint.size(), -1);
  for (int i = 0; i < n_links; ++i) {
    const auto s = std::lower_bound(joints.begin(), joints.end(), link_joint[i]) - joints.begin();
    link_slot[i] = static_cast<int>(s);
    joint_radius[s] = std::max(joint_radius[s], local_radius[i]);
  }
}

void SceneConfig::check(const pinocchio::Model& model) const {
  for (int j : link_joint) {
    scene_require(j >= 0 && j < model.njoints,
            "link_joint: joint " + std::to_string(j) + " not in the robot's model");
  }
}

Mat motion_bounds(const pinocchio::Model& model, const SceneConfig& scene) {
  std::vector<double> offset(model.njoints);
  for (int j = 0; j < model.njoints; ++j) {
    const Vec3& p = model.jointPlacements[j].translation();
    offset[j] = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  }
  Mat rho = Mat::Zero(scene.n_links, model.nv);
  for (int i = 0; i < scene.n_links; ++i) {
    int j = scene.link_joint[i];
    double length = 0.0;
    while (j > 0) {
      const auto& joint = model.joints[j];
      const double arm = length + scene.local_radius[i];
      double bound;
      if (joint.nv() > 1) {  // planar, spherical, free-flyer: rotations and translations
        bound = arm + 1.0;
      } else if (joint.shortname().rfind("JointModelP", 0) == 0) {  // prismatic
        bound = 1.0;
      } else {  // revolute
        bound = arm;
      }
      rho.block(i, joint.idx_v(), 1, joint.nv()).setConstant(bound);
      length += offset[j];
      j = static_cast<int>(model.parents[j]);
    }
  }
  return rho;
}

CollisionScene::CollisionScene(const SceneConfig& scene)
    : scene_(&scene),
      moving_of_(scene.gmodel->ngeoms, -1),
      gdata_(*scene.gmodel),
      placed_at_(scene.gmodel->ngeoms, 0),
      joint_pos_(static_cast<Eigen::Index>(scene.joints.size()), 3) {
  for (auto& request : gdata_.distanceRequests) {
    // GJK's default 1e-6 m tolerance makes hull-hull witness points jitter by that
    // much between samples; rows are derivatives, so ask for 1e-9 m.
    request.gjk_tolerance = GJK_TOLERANCE;
    request.epa_tolerance = GJK_TOLERANCE;
    // Warm start: GJK begins where the pair's last query ended (its direction and
    // support vertices). Samples are close, so it converges in fewer iterations, and
    // a hull's support search climbs from the last vertex instead of vertex 0.
    request.gjk_initial_guess = coal::GJKInitialGuess::CachedGuess;
  }
  joint_pos_.setZero();
}

void CollisionScene::move_with(const ObstacleConfig& obstacle) {
  if (!obstacle.moving()) return;
  moving_of_.at(static_cast<std::size_t>(obstacle.geometry)) = static_cast<int>(moving_.size());
  moving_.push_back(obstacle);
}

void CollisionScene::set_obstacle(const ObstacleConfig& obstacle) {
  const auto g = static_cast<std::size_t>(obstacle.geometry);
  const int at = moving_of_.at(g);
  if (at >= 0) {
    moving_[static_cast<std::size_t>(at)] = obstacle;
  } else {
    moving_of_[g] = static_cast<int>(moving_.size());
    moving_.push_back(obstacle);
  }
  placed_at_[g] = 0;  // placed again at the next sample
}

void CollisionScene::begin_sample(const pinocchio::Data& data, double t) {
  data_ = &data;
  t_ = t;
  ++sample_;
}

// Only the geometries a distance asks for are placed (a pair near its threshold: a few
// of a robot's geometries), each once per sample.
void CollisionScene::place(pinocchio::GeomIndex g) {
  if (placed_at_[g] == sample_) return;
  placed_at_[g] = sample_;
  if (moving_of_[g] >= 0) {
    gdata_.oMg[g] = moving_[static_cast<std::size_t>(moving_of_[g])].placement(t_);
    return;
  }
  const pinocchio::GeometryObject& object = scene_->gmodel->geometryObjects[g];
  // updateGeometryPlacements: oMi[joint] placement, or the placement for the world
  if (object.parentJoint > 0) {
    gdata_.oMg[g] = data_->oMi[object.parentJoint] * object.placement;
  } else {
    gdata_.oMg[g] = object.placement;
  }
}

const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& CollisionScene::place_joints(
    const pinocchio::Data& data) {
  const auto& joints = scene_->joints;
  for (size_t s = 0; s < joints.size(); ++s) {
    joint_pos_.row(static_cast<Eigen::Index>(s)) = data.oMi[joints[s]].translation().transpose();
  }
  return joint_pos_;
}

void CollisionScene::distance(int pair, PairDistance& out) {
  const auto index = static_cast<pinocchio::PairIndex>(pair);
  const pinocchio::CollisionPair& geometries = scene_->gmodel->collisionPairs[index];
  place(geometries.first);
  place(geometries.second);
  const coal::DistanceResult& res = pinocchio::computeDistance(*scene_->gmodel, gdata_, index);
  gdata_.distanceRequests[index].updateGuess(res);
  out.distance = res.min_distance;
  out.point_a = res.nearest_points[0];
  out.point_b = res.nearest_points[1];
  out.normal = res.normal;
}

}  // namespace clik
