// A cloud's voxel spheres in a uniform grid, and a link's nearest sphere within a reach
// (mirrors clik/clouds/grid.py and clik/clouds/nearest.py, step for step; docs/method.md,
// "Obstacles from point clouds", (C1)-(C2)).
//
// The grid's arrays are built by Python (clik.clouds.grid.sphere_grid) and checked here
// once (CloudConfig::check): sphere indices sorted by cell (x, then y, then z), each
// cell's start among them. A query collects the spheres of the cells met by the link's
// world box grown by the reach and the largest radius, bounds each one's distance below
// by its centre's distance to the link's own box (none for a centre inside it), and asks
// coal (the link against one sphere) in the order of that bound until it reaches the
// best distance found or the reach; a sphere that a separating plane met so far (through
// the link's nearest point to an earlier centre) keeps as far is skipped. Nothing is allocated per query: the scratch list
// is reserved for every sphere once.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <coal/collision_object.h>
#include <coal/collision_data.h>
#include <coal/shape/geometric_shapes.h>
#include <pinocchio/spatial/se3.hpp>

#include "types.hpp"

namespace clik {

// clik.clouds.nearest: coal's tolerance for a link-sphere distance [m]; the radius a
// sphere of radius 0 (a point) is given, its distance corrected by it [m].
constexpr double CLOUD_GJK_TOLERANCE = 1e-9;
constexpr double POINT_RADIUS = 1e-9;
// Separating planes a query keeps (the latest) to skip spheres they keep far.
constexpr int MAX_PLANES = 4;

struct CloudConfig {
  std::string name;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> centres;  // (K, 3) world [m]
  Vec radii;                 // (K) [m], >= 0
  double cell = 0.0;         // grid cell [m]
  Vec3 low = Vec3::Zero();   // the grid's lowest corner [m]
  Eigen::Vector3i dims = Eigen::Vector3i::Ones();  // cells along x, y, z
  Eigen::VectorXi order;     // (K) sphere indices sorted by cell
  Eigen::VectorXi start;     // (cells + 1) each cell's first position in order
  double threshold = 0.0;    // d_o [m]
  double largest = 0.0;      // the largest radius [m] (check() sets it)
  // (4, K): x, y, z [m] and radius [m] of the sphere at each position of `order`, so a
  // column of cells is read in one contiguous pass (check() sets it).
  Eigen::Matrix<double, 4, Eigen::Dynamic> by_cell;

  int size() const { return static_cast<int>(radii.size()); }
  // Sizes, finite values, the grid's arrays consistent with the centres (each sphere
  // once, in its own cell). Throws std::invalid_argument naming the cloud and the field.
  void check();
};

// A link's box in its own frame, from coal's local AABB.
struct LocalBox {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
};

struct NearestSphere {
  double distance = INF;  // d_k [m], negative inside the sphere
  Vec3 on_link = Vec3::Zero(), on_cloud = Vec3::Zero(), normal = Vec3::Zero();
  int sphere = -1;
};

class CloudQuery {
 public:
  CloudQuery();
  // Room for a cloud of `spheres` spheres (once per cloud, not per query).
  void reserve(int spheres);
  // The link's nearest sphere if nearer than `reach` [m] (clouds.nearest.nearest_sphere);
  // sphere `hint` (the pair's last nearest, -1: none) is asked first, its distance
  // narrowing the cells searched.
  bool nearest(const CloudConfig& cloud, const coal::CollisionGeometry& shape,
               const LocalBox& box, const pinocchio::SE3& placement, double reach, int hint,
               NearestSphere& out);

 private:
  struct Hit {
    double lower;  // lower bound of the sphere's distance [m]
    int position;  // order of collection (the stable sort's tie-break)
    int sphere;
  };
  struct Plane {
    Vec3 n = Vec3::Zero();  // the link lies in n . x <= offset
    double offset = 0.0;
  };
  void sphere_distance(const coal::CollisionGeometry& shape, const coal::Transform3s& tf,
                       const Vec3& centre, double radius, NearestSphere& out);
  void add_plane(const Vec3& centre, const NearestSphere& found);
  double plane_bound(const Vec3& centre) const;

  std::array<Plane, MAX_PLANES> planes_;
  int n_planes_ = 0, next_plane_ = 0;

  std::vector<Hit> hits_;
  coal::DistanceRequest request_;
  coal::DistanceResult result_;
  coal::Sphere ball_{1.0};
};

}  // namespace clik
