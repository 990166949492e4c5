#include "primitives.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rng.h"

namespace evidential_octomap::generator {

float Primitive::radiusXY() const {
  switch (shape) {
    case Shape::kCylinderZ:
      return half.x();
    default:
      return std::hypot(half.x(), half.y());
  }
}
void Primitive::setYaw(float y) {
  yaw = y;
  cos_yaw = float(std::cos(double(y)));
  sin_yaw = float(std::sin(double(y)));
  bound = shape == Shape::kEllipsoid ? half.maxCoeff() : half.norm();
}

float Primitive::zmin() const { return centre.z() - half.z(); }
float Primitive::zmax() const { return centre.z() + half.z(); }

bool Primitive::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax,
                          double* t0, double* t1, Eigen::Vector3f* normal) const {
  const double px = o.x() - centre.x(), py = o.y() - centre.y(), pz = o.z() - centre.z();
  // Bounding sphere first: most candidates of a grid cell are missed.
  const double along = -(px * d.x() + py * d.y() + pz * d.z());
  const double miss2 = px * px + py * py + pz * pz - along * along;
  if (miss2 > double(bound) * bound || along < -double(bound) || along > tmax + bound) {
    return false;
  }
  // Into the object frame: translate, rotate by -yaw.
  const double c = cos_yaw, s = sin_yaw;
  const Eigen::Vector3d p(c * px + s * py, -s * px + c * py, pz);
  const Eigen::Vector3d v(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), d.z());
  const Eigen::Vector3d h = half.cast<double>();
  double lo = 0.0, hi = tmax;
  Eigen::Vector3d n_local = Eigen::Vector3d::Zero();
  auto slab = [&](int axis) {  // clips [lo, hi] to |p + t v|_axis <= h_axis
    if (std::abs(v[axis]) < 1e-12) return std::abs(p[axis]) <= h[axis];
    double a = (-h[axis] - p[axis]) / v[axis], b = (h[axis] - p[axis]) / v[axis];
    double sign = -1.0;
    if (a > b) std::swap(a, b), sign = 1.0;
    if (a > lo) {
      lo = a;
      n_local = Eigen::Vector3d::Zero();
      n_local[axis] = sign;
    }
    hi = std::min(hi, b);
    return lo <= hi;
  };
  auto circle = [&](int a1, int a2, double r) {  // clips to the infinite cylinder around the axis
    const double A = v[a1] * v[a1] + v[a2] * v[a2];
    const double B = p[a1] * v[a1] + p[a2] * v[a2];
    const double C = p[a1] * p[a1] + p[a2] * p[a2] - r * r;
    if (A < 1e-12) return C <= 0.0;
    const double disc = B * B - A * C;
    if (disc < 0.0) return false;
    const double q = std::sqrt(disc);
    const double a = (-B - q) / A, b = (-B + q) / A;
    if (a > lo) {
      lo = a;
      n_local = Eigen::Vector3d::Zero();
      n_local[a1] = p[a1] + a * v[a1];
      n_local[a2] = p[a2] + a * v[a2];
    }
    hi = std::min(hi, b);
    return lo <= hi;
  };
  bool ok = false;
  switch (shape) {
    case Shape::kBox:
      ok = slab(0) && slab(1) && slab(2);
      break;
    case Shape::kCylinderZ:
      ok = slab(2) && circle(0, 1, h.x());
      break;
    case Shape::kCylinderX:
      ok = slab(0) && circle(1, 2, h.y());
      break;
    case Shape::kEllipsoid: {
      const Eigen::Vector3d ps = p.cwiseQuotient(h), vs = v.cwiseQuotient(h);
      const double A = vs.squaredNorm(), B = ps.dot(vs), C = ps.squaredNorm() - 1.0;
      const double disc = B * B - A * C;
      if (disc < 0.0) return false;
      const double q = std::sqrt(disc);
      const double a = (-B - q) / A, b = (-B + q) / A;
      lo = std::max(lo, a);
      hi = std::min(hi, b);
      ok = lo <= hi;
      n_local = (p + a * v).cwiseQuotient(h.cwiseProduct(h));
      break;
    }
  }
  if (!ok || hi < 0.0 || lo > tmax) return false;
  *t0 = lo;
  *t1 = hi;
  const double nn = n_local.norm();
  const Eigen::Vector3d nl = nn > 0 ? Eigen::Vector3d(n_local / nn) : Eigen::Vector3d(-v);
  // Back to the world: rotate by +yaw.
  *normal = Eigen::Vector3f(float(c * nl.x() - s * nl.y()), float(s * nl.x() + c * nl.y()),
                            float(nl.z()));
  return true;
}

void ObjectGrid::build(const std::vector<Primitive>* prims, const Grid2& extent) {
  prims_ = prims;
  grid_ = Grid2::covering(extent.x0, extent.y0, extent.x0 + extent.nx * extent.res,
                          extent.y0 + extent.ny * extent.res, kCell);
  std::vector<uint32_t> count(grid_.size() + 1, 0);
  auto forCells = [&](const Primitive& p, auto&& fn) {
    const float r = p.radiusXY();
    for (int j = grid_.iy(p.centre.y() - r); j <= grid_.iy(p.centre.y() + r); ++j)
      for (int i = grid_.ix(p.centre.x() - r); i <= grid_.ix(p.centre.x() + r); ++i)
        fn(grid_.index(i, j));
  };
  for (const Primitive& p : *prims) forCells(p, [&](size_t c) { ++count[c + 1]; });
  offsets_.assign(grid_.size() + 1, 0);
  for (size_t c = 0; c < grid_.size(); ++c) offsets_[c + 1] = offsets_[c] + count[c + 1];
  items_.resize(offsets_.back());
  std::vector<uint32_t> fill(offsets_.begin(), offsets_.end() - 1);
  cell_top_.assign(grid_.size(), -std::numeric_limits<float>::infinity());
  for (uint32_t k = 0; k < prims->size(); ++k) {
    const Primitive& p = (*prims)[k];
    forCells(p, [&](size_t c) {
      items_[fill[c]++] = k;
      cell_top_[c] =
          std::max(cell_top_[c], p.zmax() + (p.shape == Shape::kEllipsoid ? 0.0f : 0.5f));
    });
  }
}

bool ObjectGrid::cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax,
                      uint64_t ray_key, ObjectHit* hit) const {
  if (items_.empty()) return false;
  // 2-D DDA (Amanatides & Woo) over the cells the ray's xy projection crosses.
  const double res = grid_.res;
  double gx = (o.x() - grid_.x0) / res, gy = (o.y() - grid_.y0) / res;
  // Clip the start into the grid.
  double t_start = 0.0;
  {
    double lo = 0.0, hi = tmax;
    const double ext[2] = {double(grid_.nx), double(grid_.ny)};
    const double g[2] = {gx, gy}, v[2] = {d.x() / res, d.y() / res};
    for (int a = 0; a < 2; ++a) {
      if (std::abs(v[a]) < 1e-12) {
        if (g[a] < 0 || g[a] >= ext[a]) return false;
        continue;
      }
      double t0 = (0.0 - g[a]) / v[a], t1 = (ext[a] - g[a]) / v[a];
      if (t0 > t1) std::swap(t0, t1);
      lo = std::max(lo, t0);
      hi = std::min(hi, t1);
    }
    if (lo > hi) return false;
    t_start = lo;
    tmax = hi;
  }
  const double vx = d.x() / res, vy = d.y() / res;
  int i = std::clamp(int(std::floor(gx + t_start * vx)), 0, grid_.nx - 1);
  int j = std::clamp(int(std::floor(gy + t_start * vy)), 0, grid_.ny - 1);
  const int si = vx > 0 ? 1 : -1, sj = vy > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  const double dti = std::abs(vx) > 1e-12 ? 1.0 / std::abs(vx) : inf;
  const double dtj = std::abs(vy) > 1e-12 ? 1.0 / std::abs(vy) : inf;
  double ti = std::abs(vx) > 1e-12 ? ((si > 0 ? i + 1 : i) - gx) / vx : inf;
  double tj = std::abs(vy) > 1e-12 ? ((sj > 0 ? j + 1 : j) - gy) / vy : inf;
  double best = tmax;
  bool found = false;
  double t_cell = t_start;
  while (true) {
    const double t_exit = std::min({ti, tj, tmax});
    const size_t c = grid_.index(i, j);
    // Skip the cell when the ray stays above everything in it.
    const double z_low = o.z() + d.z() * (d.z() > 0 ? t_cell : t_exit);
    if (z_low <= cell_top_[c]) {
      for (uint32_t k = offsets_[c]; k < offsets_[c + 1]; ++k) {
        const Primitive& p = (*prims_)[items_[k]];
        double t0, t1;
        Eigen::Vector3f n;
        if (!p.intersect(o, d, best, &t0, &t1, &n)) continue;
        double t = std::max(t0, 0.0);
        bool porous = false;
        if (p.density > 0.0f) {
          const double u = unitOf(hashOf(ray_key, kStreamFoliage, p.id));
          t += -std::log(1.0 - u) / p.density;
          if (t > t1) continue;  // passed through the foliage
          porous = true;
        }
        if (t < best) {
          best = t;
          found = true;
          *hit = {t, items_[k], n, porous};
        }
      }
    }
    if (found && best <= t_exit) return true;
    if (t_exit >= tmax) return found;
    t_cell = t_exit;
    if (ti < tj) {
      i += si;
      ti += dti;
      if (i < 0 || i >= grid_.nx) return found;
    } else {
      j += sj;
      tj += dtj;
      if (j < 0 || j >= grid_.ny) return found;
    }
  }
}

}  // namespace evidential_octomap::generator
