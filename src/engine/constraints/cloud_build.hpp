// A cloud's voxel spheres and their grid built from its points, in the engine
// (clik/clouds/voxels.py, clik/clouds/grid.py, step for step): a controller's cloud
// update (Controller.update_cloud) costs one pass and two sorts over the points here.
#pragma once

#include <string>

#include "constraints/cloud_query.hpp"
#include "types.hpp"

namespace clik {

// clik.clouds.grid: the most cells along a cloud's longest side, the smallest cell [m].
constexpr int MAX_GRID_SPAN = 128;
constexpr double MIN_CELL = 1e-3;

// The voxel spheres (C1) of `points` (N, 3) [m] in the cloud's frame (rows with a NaN or
// an infinity dropped; `dropped` counts them), voxel edge `voxel` [m] (0: each point a
// sphere of radius 0), placed in the world by (rotation, position), in their grid for
// `threshold` [m]. Throws std::invalid_argument on a bad voxel or threshold.
CloudConfig build_cloud(const std::string& name,
                        const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 3,
                                                            Eigen::RowMajor>>& points,
                        double voxel, const Mat3& rotation, const Vec3& position,
                        double threshold, int& dropped);

}  // namespace clik
