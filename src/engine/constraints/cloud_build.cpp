// A cloud's voxel spheres and grid: see cloud_build.hpp.
#include "constraints/cloud_build.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace clik {

namespace {

using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Indices 0..n sorted by key, equal keys in their order (numpy's stable argsort).
std::vector<int> stable_order(const std::vector<long long>& key) {
  std::vector<int> order(key.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });
  return order;
}

// clouds.voxels.voxel_spheres: centres (cloud frame) and radii.
void voxel_spheres(const Rows& pts, double voxel, Rows& centres, Vec& radii) {
  const auto n = static_cast<int>(pts.rows());
  if (voxel == 0.0 || n == 0) {
    centres = pts;
    radii = Vec::Zero(n);
    return;
  }
  Eigen::Matrix<long long, Eigen::Dynamic, 3, Eigen::RowMajor> keys(n, 3);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) keys(i, a) = static_cast<long long>(std::floor(pts(i, a) / voxel));
  }
  const Eigen::Matrix<long long, 1, 3> low = keys.colwise().minCoeff();
  const Eigen::Matrix<long long, 1, 3> span =
      keys.colwise().maxCoeff() - low + Eigen::Matrix<long long, 1, 3>::Ones();
  std::vector<long long> flat(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    flat[i] = ((keys(i, 0) - low[0]) * span[1] + (keys(i, 1) - low[1])) * span[2] +
              (keys(i, 2) - low[2]);
  }
  const std::vector<int> order = stable_order(flat);
  std::vector<int> starts;
  for (int j = 0; j < n; ++j) {
    if (j == 0 || flat[order[j]] != flat[order[j - 1]]) starts.push_back(j);
  }
  const auto k = static_cast<int>(starts.size());
  centres.resize(k, 3);
  radii.resize(k);
  for (int s = 0; s < k; ++s) {
    const int a = starts[s], b = s + 1 < k ? starts[s + 1] : n;
    Vec3 sum = pts.row(order[a]).transpose();
    for (int j = a + 1; j < b; ++j) sum += pts.row(order[j]).transpose();
    const Vec3 c = sum / static_cast<double>(b - a);
    centres.row(s) = c.transpose();
    double r = 0.0;
    for (int j = a; j < b; ++j) {
      const Vec3 g = pts.row(order[j]).transpose() - c;
      r = std::max(r, std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
    }
    radii[s] = r;
  }
}

// clouds.grid.grid_cell and sphere_grid.
void fill_grid(CloudConfig& cloud) {
  const auto k = static_cast<int>(cloud.radii.size());
  const double largest = k > 0 ? cloud.radii.maxCoeff() : 0.0;
  Vec3 low = Vec3::Zero(), high = Vec3::Zero();
  if (k > 0) {
    low = cloud.centres.colwise().minCoeff().transpose();
    high = cloud.centres.colwise().maxCoeff().transpose();
  }
  const double extent = k > 0 ? (high - low).maxCoeff() : 0.0;
  cloud.cell = std::max({2.0 * largest, extent / MAX_GRID_SPAN, MIN_CELL});
  cloud.low = low;
  for (int a = 0; a < 3; ++a) {
    cloud.dims[a] = static_cast<int>(std::floor((high[a] - low[a]) / cloud.cell)) + 1;
  }
  std::vector<long long> flat(static_cast<std::size_t>(k));
  for (int s = 0; s < k; ++s) {
    long long at[3];
    for (int a = 0; a < 3; ++a) {
      const auto f = static_cast<long long>(std::floor((cloud.centres(s, a) - low[a]) / cloud.cell));
      at[a] = std::min(f, static_cast<long long>(cloud.dims[a]) - 1);
    }
    flat[s] = (at[0] * cloud.dims[1] + at[1]) * cloud.dims[2] + at[2];
  }
  const std::vector<int> order = stable_order(flat);
  const long long cells = static_cast<long long>(cloud.dims[0]) * cloud.dims[1] * cloud.dims[2];
  cloud.order = Eigen::Map<const Eigen::VectorXi>(order.data(), k);
  cloud.start = Eigen::VectorXi::Zero(cells + 1);
  for (int s = 0; s < k; ++s) ++cloud.start[flat[s] + 1];
  for (long long c = 0; c < cells; ++c) cloud.start[c + 1] += cloud.start[c];
}

}  // namespace

CloudConfig build_cloud(const std::string& name, const Eigen::Ref<const Rows>& points,
                        double voxel, const Mat3& rotation, const Vec3& position,
                        double threshold, int& dropped) {
  if (!(std::isfinite(voxel) && voxel >= 0.0)) {
    throw std::invalid_argument("build_cloud " + name + ": voxel a finite size >= 0 [m]");
  }
  if (!rotation.allFinite() || !position.allFinite()) {
    throw std::invalid_argument("build_cloud " + name + ": a finite pose");
  }
  Rows kept(points.rows(), 3);
  int n = 0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    if (points.row(i).allFinite()) kept.row(n++) = points.row(i);
  }
  dropped = static_cast<int>(points.rows()) - n;
  kept.conservativeResize(n, 3);
  CloudConfig cloud;
  cloud.name = name;
  cloud.threshold = threshold;
  Rows local;
  voxel_spheres(kept, voxel, local, cloud.radii);
  cloud.centres.resize(local.rows(), 3);
  for (Eigen::Index s = 0; s < local.rows(); ++s) {  // points @ rotation.T + position
    const Vec3 c = local.row(s).transpose();
    for (int a = 0; a < 3; ++a) {
      cloud.centres(s, a) =
          c[0] * rotation(a, 0) + c[1] * rotation(a, 1) + c[2] * rotation(a, 2) + position[a];
    }
  }
  fill_grid(cloud);
  cloud.check();
  return cloud;
}

}  // namespace clik
