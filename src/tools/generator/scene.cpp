#include "scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "noise.h"
#include "rng.h"

namespace evidential_octomap::generator {

namespace {

constexpr double kTwoPi = 6.283185307179586;

class Placer {
 public:
  Placer(Scene* scene, const std::vector<Mover>& movers, uint64_t key)
      : s_(*scene), movers_(movers), key_(key) {}

  // Calls fn(x, y, hash) at one jittered point of each `cell`-metre cell with probability p,
  // where the point is at least `clear` metres from the route and from the movers' paths.
  template <typename Fn>
  void scatter(uint64_t what, double cell, double p, double clear, Fn&& fn) {
    const Grid2& e = s_.extent;
    const int i0 = int(std::floor(e.x0 / cell)), i1 = int(std::ceil((e.x0 + e.nx * e.res) / cell));
    const int j0 = int(std::floor(e.y0 / cell)), j1 = int(std::ceil((e.y0 + e.ny * e.res) / cell));
    for (int j = j0; j < j1; ++j) {
      for (int i = i0; i < i1; ++i) {
        const uint64_t h = hashOf(key_, what, uint64_t(int64_t(i)), uint64_t(int64_t(j)));
        if (unitOf(h) >= p) continue;
        const double x = (i + unitOf(hashOf(h, 1))) * cell, y = (j + unitOf(hashOf(h, 2))) * cell;
        if (!e.inside(x, y) || !clearOf(x, y, clear)) continue;
        fn(x, y, h);
      }
    }
  }
  bool clearOf(double x, double y, double clear) const {
    if (s_.path.distance(x, y) < clear) return false;
    for (const Mover& m : movers_) {
      const double need = m.kind == Kind::kVehicle ? 3.5 : 1.2;
      if (m.distanceToPath({x, y}) < need + 0.5 * std::max(0.0, clear - 2.0)) return false;
    }
    return true;
  }
  double ground(double x, double y) const { return s_.terrain.groundHeight(x, y); }
  void add(Shape shape, Kind kind, Eigen::Vector3d c, Eigen::Vector3d half, double yaw,
           float density = 0.0f, float reflect_jitter = 0.0f) {
    Primitive p;
    p.shape = shape;
    p.kind = kind;
    p.density = density;
    p.centre = c.cast<float>();
    p.half = half.cast<float>();
    p.setYaw(float(yaw));
    p.id = uint32_t(s_.objects.size() + 1);
    p.reflectivity = kindInfo(kind).reflectivity * (1.0f + reflect_jitter);
    s_.objects.push_back(p);
  }
  static double u(uint64_t h, uint64_t k) { return unitOf(hashOf(h, k)); }

  void tree(double x, double y, uint64_t h, double scale = 1.0) {
    const double g = ground(x, y);
    const bool conifer = u(h, 10) < 0.5;
    const double trunk_r = (0.12 + 0.23 * u(h, 11)) * scale;
    const double crown_r = (conifer ? 1.2 + 1.0 * u(h, 12) : 1.8 + 1.4 * u(h, 12)) * scale;
    const double crown_h = (conifer ? 3.5 + 3.0 * u(h, 13) : 2.0 + 2.0 * u(h, 13)) * scale;
    const double crown_base = (conifer ? 1.2 + 1.5 * u(h, 14) : 2.0 + 2.5 * u(h, 14)) * scale;
    const double top = crown_base + 2.0 * crown_h * 0.9;
    const float jitter = float(u(h, 15) - 0.5) * 0.3f;
    add(Shape::kCylinderZ, Kind::kTree, {x, y, g + 0.5 * top - 0.3},
        {trunk_r, trunk_r, 0.5 * top + 0.3}, 0.0, 0.0f, jitter);
    add(Shape::kEllipsoid, Kind::kTree, {x, y, g + crown_base + crown_h},
        {crown_r, crown_r * (0.85 + 0.3 * u(h, 16)), crown_h}, kTwoPi * u(h, 17),
        float(0.3 + 0.6 * u(h, 18)), jitter);
  }
  void bush(double x, double y, uint64_t h, double scale = 1.0) {
    const double rx = (0.5 + 1.0 * u(h, 20)) * scale, ry = rx * (0.7 + 0.5 * u(h, 21));
    const double rz = (0.35 + 0.6 * u(h, 22)) * scale;
    add(Shape::kEllipsoid, Kind::kBush, {x, y, ground(x, y) + 0.65 * rz}, {rx, ry, rz},
        kTwoPi * u(h, 23), float(1.8 + 1.5 * u(h, 24)), float(u(h, 25) - 0.5) * 0.3f);
  }
  void rock(double x, double y, uint64_t h, Kind kind, double rmin, double rmax) {
    const double r = rmin + (rmax - rmin) * u(h, 30);
    const Eigen::Vector3d half(r * (0.8 + 0.4 * u(h, 31)), r * (0.7 + 0.4 * u(h, 32)),
                               r * (0.45 + 0.35 * u(h, 33)));
    // Partly buried, like real rocks.
    add(Shape::kEllipsoid, kind, {x, y, ground(x, y) + 0.35 * half.z()}, half, kTwoPi * u(h, 34),
        0.0f, float(u(h, 35) - 0.5) * 0.4f);
  }
  void log(double x, double y, uint64_t h) {
    const double r = 0.12 + 0.18 * u(h, 40), len = 2.0 + 4.0 * u(h, 41);
    add(Shape::kCylinderX, Kind::kLog, {x, y, ground(x, y) + 0.8 * r}, {0.5 * len, r, r},
        kTwoPi * u(h, 42), 0.0f, float(u(h, 43) - 0.5) * 0.3f);
  }
  void vehicle(double x, double y, double yaw, uint64_t h) {
    add(Shape::kBox, Kind::kVehicle, {x, y, ground(x, y) + 0.8 + 0.15}, {2.25, 0.95, 0.8}, yaw,
        0.0f, float(u(h, 50) - 0.5) * 1.2f);
  }

 private:
  Scene& s_;
  const std::vector<Mover>& movers_;
  uint64_t key_;
};

void placeForest(Scene* s, Placer& P, double w) {
  P.scatter(1, 5.0, 0.6, w + 1.2, [&](double x, double y, uint64_t h) { P.tree(x, y, h); });
  P.scatter(2, 4.0, 0.45, w + 0.4, [&](double x, double y, uint64_t h) { P.bush(x, y, h); });
  P.scatter(3, 12.0, 0.35, w + 0.6, [&](double x, double y, uint64_t h) { P.log(x, y, h); });
  (void)s;
}

void placeGrassland(Scene*, Placer& P, double w) {
  P.scatter(2, 14.0, 0.35, w + 0.8, [&](double x, double y, uint64_t h) { P.bush(x, y, h, 1.3); });
}

void placeRocky(Scene*, Placer& P, double w) {
  P.scatter(4, 10.0, 0.45, w + 1.5,
            [&](double x, double y, uint64_t h) { P.rock(x, y, h, Kind::kBoulder, 0.9, 2.6); });
  P.scatter(5, 3.0, 0.5, w + 0.3,
            [&](double x, double y, uint64_t h) { P.rock(x, y, h, Kind::kRock, 0.15, 0.55); });
  P.scatter(2, 9.0, 0.3, w + 0.5, [&](double x, double y, uint64_t h) { P.bush(x, y, h); });
  P.scatter(1, 20.0, 0.3, w + 1.5, [&](double x, double y, uint64_t h) { P.tree(x, y, h, 0.8); });
}

void placeFarm(Scene* s, Placer& P, double w, const Route& route, double a0, double a1,
               uint64_t key) {
  // Along the road: a fence on one side (posts every 2.5 m, two rails, gaps), utility poles on
  // the other, parked vehicles on the verge.
  const double fence_side = unitOf(hashOf(key, 60)) < 0.5 ? 1.0 : -1.0;
  const double fence_off = w + 3.0 + 2.0 * unitOf(hashOf(key, 61));
  for (double a = 2.5 * std::floor(a0 / 2.5); a + 2.5 < a1; a += 2.5) {
    if (fbm2(hashOf(key, 62), a, 0.0, 40.0, 2) < -0.25) continue;  // a gap (gate, field entry)
    const Eigen::Vector2d t = route.tangent(a), n(-t.y(), t.x());
    const Eigen::Vector2d p = route.at(a) + fence_side * fence_off * n;
    const Eigen::Vector2d q = route.at(a + 2.5) + fence_side * fence_off * n;
    if (!P.clearOf(p.x(), p.y(), w + 1.0)) continue;
    const double g = P.ground(p.x(), p.y());
    P.add(Shape::kCylinderZ, Kind::kFence, {p.x(), p.y(), g + 0.6}, {0.06, 0.06, 0.7}, 0.0);
    const Eigen::Vector2d m = 0.5 * (p + q);
    const double len = (q - p).norm(), yaw = std::atan2(q.y() - p.y(), q.x() - p.x());
    const double gm = P.ground(m.x(), m.y());
    for (double z : {0.55, 1.05}) {
      P.add(Shape::kBox, Kind::kFence, {m.x(), m.y(), gm + z}, {0.5 * len, 0.025, 0.06}, yaw);
    }
  }
  for (double a = 38.0 * std::floor(a0 / 38.0) + 15.0; a < a1; a += 38.0) {
    const Eigen::Vector2d t = route.tangent(a), n(-t.y(), t.x());
    const Eigen::Vector2d p = route.at(a) - fence_side * (w + 3.5) * n;
    if (!P.clearOf(p.x(), p.y(), w + 2.0)) continue;
    P.add(Shape::kCylinderZ, Kind::kPole, {p.x(), p.y(), P.ground(p.x(), p.y()) + 4.0},
          {0.14, 0.14, 4.3}, 0.0);
  }
  for (double a = 55.0 * std::floor(a0 / 55.0) + 30.0; a < a1; a += 55.0) {
    const uint64_t h = hashOf(key, 63, uint64_t(int64_t(a)));
    if (unitOf(h) > 0.4) continue;
    const Eigen::Vector2d t = route.tangent(a), n(-t.y(), t.x());
    const Eigen::Vector2d p = route.at(a) - fence_side * (w + 2.0) * n;
    if (!P.clearOf(p.x(), p.y(), w + 1.4)) continue;
    P.vehicle(p.x(), p.y(), std::atan2(t.y(), t.x()), h);
  }
  // Farm buildings with a concrete slab in front and a vehicle parked by some of them.
  P.scatter(6, 45.0, 0.45, w + 14.0, [&](double x, double y, uint64_t h) {
    const double lx = 4.0 + 6.0 * Placer::u(h, 70), ly = 3.0 + 5.0 * Placer::u(h, 71);
    const double hz = 1.5 + 2.0 * Placer::u(h, 72), yaw = kTwoPi * Placer::u(h, 73);
    // The lowest ground under the footprint, so the building sits on (into) the slope.
    double g = P.ground(x, y);
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0}) g = std::min(g, P.ground(x + sx * lx, y + sy * ly));
    P.add(Shape::kBox, Kind::kBuilding, {x, y, g + hz - 0.3}, {lx, ly, hz + 0.3}, yaw);
    const double c = std::cos(yaw), s = std::sin(yaw);
    const Eigen::Vector2d front(x + c * (lx + 3.0), y + s * (lx + 3.0));
    P.add(Shape::kBox, Kind::kConcrete,
          {front.x(), front.y(), P.ground(front.x(), front.y()) + 0.02}, {3.0, 0.8 * ly, 0.12},
          yaw);
    if (Placer::u(h, 74) < 0.6) {
      const Eigen::Vector2d v(front.x() - s * (0.8 * ly + 2.0), front.y() + c * (0.8 * ly + 2.0));
      P.vehicle(v.x(), v.y(), yaw + 1.5707963, h);
    }
  });
  P.scatter(1, 16.0, 0.3, w + 2.5, [&](double x, double y, uint64_t h) { P.tree(x, y, h); });
  P.scatter(2, 10.0, 0.25, w + 1.0, [&](double x, double y, uint64_t h) { P.bush(x, y, h); });
  (void)s;
}

}  // namespace

std::unique_ptr<Scene> Scene::build(Family family, uint64_t seed, const Route& route,
                                    double max_arc, double margin, const std::vector<Mover>& movers,
                                    const KindClasses& classes) {
  auto owned = std::make_unique<Scene>();
  Scene& s = *owned;
  s.family = family;
  s.seed = seed;
  double xmin = 1e18, ymin = 1e18, xmax = -1e18, ymax = -1e18;
  const size_t n = std::min(route.xy.size(), size_t(max_arc / route.step) + 2);
  for (size_t k = 0; k < n; ++k) {
    xmin = std::min(xmin, route.xy[k].x()), xmax = std::max(xmax, route.xy[k].x());
    ymin = std::min(ymin, route.xy[k].y()), ymax = std::max(ymax, route.xy[k].y());
  }
  s.extent = Grid2::covering(xmin - margin, ymin - margin, xmax + margin, ymax + margin,
                             Terrain::kResolution);
  // About 20 B per terrain cell in all (terrain, path field, border map): 1.2 GB at this bound.
  if (s.extent.size() > size_t(60e6)) {
    throw std::invalid_argument(
        "the route spans " + std::to_string(int(s.extent.nx * s.extent.res)) + " m x " +
        std::to_string(int(s.extent.ny * s.extent.res)) +
        " m with its margin, more than the generator holds (3.75 km^2): use --route loop or "
        "out-and-back (revisits), a shorter --route-length or fewer --scans");
  }
  // The trail exists beyond the part driven: 60 m ahead (and behind the start of a loop).
  double a0 = 0.0, a1 = std::min(max_arc + 60.0, route.length);
  if (route.kind == RouteKind::kLoop) {
    a0 = -60.0, a1 = max_arc + 60.0;
    if (a1 - a0 > route.length) a0 = 0.0, a1 = route.length;
  }
  s.path = PathField::make(
      route, a0, a1,
      Grid2::covering(xmin - margin, ymin - margin, xmax + margin, ymax + margin, 0.5));
  s.terrain = Terrain::build(family, seed, s.extent, route, s.path);
  const uint64_t key = hashOf(seed, kStreamObjects);
  Placer P(&s, movers, key);
  const double w = s.terrain.params().trail_half_width;
  switch (family) {
    case Family::kForest:
      placeForest(&s, P, w);
      break;
    case Family::kGrassland:
      placeGrassland(&s, P, w);
      break;
    case Family::kRocky:
      placeRocky(&s, P, w);
      break;
    case Family::kFarm:
      placeFarm(&s, P, w, route, a0, a1, key);
      break;
  }
  s.object_grid.build(&s.objects, s.extent);
  int C = 0;
  for (int c : classes.cls) C = std::max(C, c + 1);
  s.borders.build(s.terrain, s.objects, classes, C);
  return owned;
}

}  // namespace evidential_octomap::generator
