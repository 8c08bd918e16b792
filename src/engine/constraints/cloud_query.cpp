// A cloud's grid and a link's nearest sphere: see cloud_query.hpp.
#include "constraints/cloud_query.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <coal/distance.h>

namespace clik {

namespace {

constexpr long long MAX_CELLS = 1LL << 26;

[[noreturn]] void refuse(const std::string& cloud, const std::string& what) {
  throw std::invalid_argument("CloudConfig " + cloud + ": " + what);
}

}  // namespace

void CloudConfig::check() {
  const auto k = static_cast<Eigen::Index>(radii.size());
  if (name.empty()) refuse(name, "a name");
  if (centres.rows() != k || order.size() != k) refuse(name, "K centres (K, 3), K radii, K order");
  if (!centres.allFinite() || !radii.allFinite() || (k > 0 && radii.minCoeff() < 0.0)) {
    refuse(name, "finite centres [m] and finite radii >= 0 [m]");
  }
  if (!(std::isfinite(cell) && cell > 0.0) || !low.allFinite()) {
    refuse(name, "a positive grid cell [m] and a finite lowest corner");
  }
  if (!(std::isfinite(threshold) && threshold > 0.0)) refuse(name, "a positive threshold [m]");
  if (dims.minCoeff() < 1) refuse(name, "at least one cell along each axis");
  const long long cells = static_cast<long long>(dims[0]) * dims[1] * dims[2];
  if (cells > MAX_CELLS) refuse(name, "at most 2^26 grid cells");
  if (start.size() != cells + 1 || start[0] != 0 || start[cells] != k) {
    refuse(name, "start: cells + 1 offsets from 0 to K");
  }
  std::vector<char> seen(static_cast<std::size_t>(k), 0);
  for (long long c = 0; c < cells; ++c) {
    if (start[c + 1] < start[c]) refuse(name, "start: offsets that never decrease");
    const long long z = c % dims[2], y = (c / dims[2]) % dims[1], x = c / (dims[2] * dims[1]);
    for (int p = start[c]; p < start[c + 1]; ++p) {
      const int s = order[p];
      if (s < 0 || s >= k || seen[static_cast<std::size_t>(s)]) {
        refuse(name, "order: each sphere's index once");
      }
      seen[static_cast<std::size_t>(s)] = 1;
      for (int a = 0; a < 3; ++a) {  // the sphere's cell, as sphere_grid computes it
        const double f = std::floor((centres(s, a) - low[a]) / cell);
        const long long at = std::min(static_cast<long long>(std::max(f, 0.0)),
                                      static_cast<long long>(dims[a]) - 1);
        if (f < 0.0 || at != (a == 0 ? x : a == 1 ? y : z)) {
          refuse(name, "order: every sphere in the cell of its centre");
        }
      }
    }
  }
  largest = k > 0 ? radii.maxCoeff() : 0.0;
  by_cell.resize(4, k);
  for (Eigen::Index p = 0; p < k; ++p) {
    by_cell.col(p) << centres.row(order[p]).transpose(), radii[order[p]];
  }
}

CloudQuery::CloudQuery() {
  request_.enable_signed_distance = true;
  request_.gjk_tolerance = CLOUD_GJK_TOLERANCE;
  request_.epa_tolerance = CLOUD_GJK_TOLERANCE;
}

void CloudQuery::reserve(int spheres) {
  hits_.reserve(static_cast<std::size_t>(std::max(spheres, 0)));
}

bool CloudQuery::nearest(const CloudConfig& cloud, const coal::CollisionGeometry& shape,
                         const LocalBox& box, const pinocchio::SE3& placement, double reach,
                         int hint, NearestSphere& out) {
  out = NearestSphere{};
  if (cloud.size() == 0) return false;
  const Mat3& R = placement.rotation();
  const Vec3& t = placement.translation();
  const coal::Transform3s tf(R, t);
  n_planes_ = next_plane_ = 0;
  if (hint >= 0 && hint < cloud.size()) {  // the pair's last nearest sphere, asked first
    const Vec3 c = cloud.centres.row(hint).transpose();
    sphere_distance(shape, tf, c, cloud.radii[hint], out);
    out.sphere = hint;
    add_plane(c, out);
  }
  const double first_bar = std::min(out.distance, reach);
  const Vec3 centre = R * (0.5 * (box.lo + box.hi)) + t;
  const Vec3 half =
      R.cwiseAbs() * (0.5 * (box.hi - box.lo)) + Vec3::Constant(first_bar + cloud.largest);
  long long a[3], b[3];
  for (int k = 0; k < 3; ++k) {
    const double fa = std::floor((centre[k] - half[k] - cloud.low[k]) / cloud.cell);
    const double fb = std::floor((centre[k] + half[k] - cloud.low[k]) / cloud.cell);
    if (fb < 0.0 || fa >= cloud.dims[k]) return false;
    a[k] = static_cast<long long>(std::max(fa, 0.0));
    b[k] = std::min(static_cast<long long>(fb), static_cast<long long>(cloud.dims[k]) - 1);
  }
  hits_.clear();
  const long long ny = cloud.dims[1], nz = cloud.dims[2];
  for (long long x = a[0]; x <= b[0]; ++x) {
    for (long long y = a[1]; y <= b[1]; ++y) {
      const long long column = (x * ny + y) * nz;
      for (int p = cloud.start[column + a[2]]; p < cloud.start[column + b[2] + 1]; ++p) {
        const double* c = cloud.by_cell.col(p).data();  // x, y, z, radius
        const double dx = c[0] - t[0], dy = c[1] - t[1], dz = c[2] - t[2];
        double g2 = 0.0;  // squared gap to the link's box, in its frame (R^T (c - t))
        for (int k = 0; k < 3; ++k) {
          const double local = R(0, k) * dx + R(1, k) * dy + R(2, k) * dz;
          const double out = std::max(std::max(box.lo[k] - local, local - box.hi[k]), 0.0);
          g2 += out * out;
        }
        double lower = -INF;  // a centre inside the box: no bound of its own
        if (g2 > 0.0) {
          const double within = first_bar + c[3];  // lower < first_bar: gap < within
          if (within <= 0.0 || g2 >= within * within) continue;
          lower = std::sqrt(g2) - c[3];
        }
        const int s = cloud.order[p];
        if (s == hint) continue;
        if (n_planes_ > 0) lower = std::max(lower, plane_bound(Vec3(c[0], c[1], c[2])) - c[3]);
        if (lower < first_bar) hits_.push_back({lower, static_cast<int>(hits_.size()), s});
      }
    }
  }
  std::sort(hits_.begin(), hits_.end(), [](const Hit& u, const Hit& v) {
    return u.lower < v.lower || (u.lower == v.lower && u.position < v.position);
  });
  NearestSphere found;
  for (const Hit& h : hits_) {
    const double bar = std::min(out.distance, reach);
    if (h.lower >= bar) break;  // none left nearer, nor in reach
    const Vec3 centre = cloud.centres.row(h.sphere).transpose();
    const double radius = cloud.radii[h.sphere];
    if (n_planes_ > 0 && plane_bound(centre) - radius >= bar) continue;  // a plane keeps it
    sphere_distance(shape, tf, centre, radius, found);
    if (found.distance < out.distance) {
      out = found;
      out.sphere = h.sphere;
    }
    add_plane(centre, found);
  }
  return out.distance < reach;
}

// clouds.nearest.separating_plane: the link lies in n . x <= offset (centre outside it).
void CloudQuery::add_plane(const Vec3& centre, const NearestSphere& found) {
  const Vec3 gap = centre - found.on_link;
  const double norm = std::sqrt(gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2]);
  if (!(found.distance > 0.0) || norm <= 0.0) return;
  const Vec3 n = gap / norm;
  const double offset = n[0] * found.on_link[0] + n[1] * found.on_link[1] + n[2] * found.on_link[2];
  Plane& p = planes_[static_cast<std::size_t>(next_plane_)];
  p = {n, offset};
  next_plane_ = (next_plane_ + 1) % MAX_PLANES;
  n_planes_ = std::min(n_planes_ + 1, MAX_PLANES);
}

// clouds.nearest.plane_bound: the largest gap of the centre beyond a plane [m].
double CloudQuery::plane_bound(const Vec3& c) const {
  double bound = -INF;
  for (int j = 0; j < n_planes_; ++j) {
    const Plane& p = planes_[static_cast<std::size_t>(j)];
    bound = std::max(bound, p.n[0] * c[0] + p.n[1] * c[1] + p.n[2] * c[2] - p.offset);
  }
  return bound;
}

void CloudQuery::sphere_distance(const coal::CollisionGeometry& shape,
                                 const coal::Transform3s& tf, const Vec3& centre,
                                 double radius, NearestSphere& out) {
  const double ball = std::max(radius, POINT_RADIUS);
  ball_.radius = ball;
  result_.clear();
  coal::distance(&shape, tf, &ball_, coal::Transform3s(Mat3::Identity(), centre), request_,
                 result_);
  out.distance = result_.min_distance + (ball - radius);
  out.on_link = result_.nearest_points[0];
  out.on_cloud = result_.nearest_points[1];
  out.normal = result_.normal;
}

}  // namespace clik
