#include "lidar.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "agents.h"
#include "primitives.h"
#include "rng.h"
#include "scene.h"
#include "trajectory.h"

namespace evidential_octomap::generator {

namespace {
constexpr double kPi = 3.141592653589793;
constexpr uint32_t kMoverObject = 0x10000;
}  // namespace

double SensorModel::angularSpacing() const {
  const double vertical =
      (elevation_deg.front() - elevation_deg.back()) / std::max(1, beams() - 1) * kPi / 180.0;
  return std::sqrt(vertical * 2.0 * kPi / columns);
}

SensorModel SensorModel::make(const std::string& name, int columns, double range_sigma) {
  SensorModel s;
  s.name = name;
  if (name == "hdl-64") {
    for (int i = 0; i < 32; ++i) s.elevation_deg.push_back(2.0 - i * (10.33 / 31.0));
    for (int i = 0; i < 32; ++i) s.elevation_deg.push_back(-8.87 - i * (16.03 / 31.0));
    s.columns = 2048;
    s.range_sigma = 0.02;
    s.range_10pct = 50.0;
  } else if (name == "os1-32" || name == "os1-64" || name == "os1-128") {
    const int n = std::stoi(name.substr(4));
    for (int i = 0; i < n; ++i) s.elevation_deg.push_back(22.5 - i * 45.0 / (n - 1));
    s.columns = 1024;
    s.range_sigma = 0.025;
    s.range_10pct = 45.0;
  } else {
    throw std::invalid_argument("unknown sensor '" + name + "' (hdl-64, os1-32, os1-64, os1-128)");
  }
  if (columns > 0) s.columns = columns;
  if (range_sigma >= 0.0) s.range_sigma = range_sigma;
  return s;
}

std::vector<LidarPoint> castScan(const Scene& scene, const Trajectory& trajectory,
                                 const std::vector<Mover>& movers, const SensorModel& sensor,
                                 int scan, double t_end, const CastOptions& options,
                                 const Eigen::Isometry3d& T_end) {
  const int B = sensor.beams(), W = sensor.columns;
  const double period = 1.0 / sensor.rate_hz;
  std::vector<double> sin_el(B), cos_el(B);
  for (int b = 0; b < B; ++b) {
    sin_el[b] = std::sin(sensor.elevation_deg[b] * kPi / 180.0);
    cos_el[b] = std::cos(sensor.elevation_deg[b] * kPi / 180.0);
  }
  // Movers present during the sweep and near enough to be seen.
  std::vector<const Mover*> near;
  for (const Mover& m : movers) {
    if (m.tEnd() < t_end - period || m.t_start > t_end) continue;
    const Eigen::Vector3d c = m.centre(t_end, scene.terrain);
    if ((c - T_end.translation()).head<2>().norm() < sensor.max_range + m.length) {
      near.push_back(&m);
    }
  }
  const Eigen::Isometry3d T_end_inv = T_end.inverse();
  std::vector<std::vector<LidarPoint>> per_column(W);

#pragma omp parallel for schedule(dynamic, 16)
  for (int c = 0; c < W; ++c) {
    // Ouster and Velodyne spin clockwise seen from above; column 0 looks backwards.
    const double azimuth = kPi - 2.0 * kPi * (c + 0.5) / W;
    const double t_fire =
        options.motion_distortion ? t_end - period + period * (c + 0.5) / W : t_end;
    const Eigen::Isometry3d T = options.motion_distortion ? trajectory.pose(t_fire) : T_end;
    const Eigen::Vector3d o = T.translation();
    // Mover boxes at this column's time.
    std::vector<Primitive> boxes;
    std::vector<uint32_t> box_instance;
    for (const Mover* m : near) {
      if (!m->present(t_fire)) continue;
      Primitive p;
      p.shape = Shape::kBox;
      p.kind = m->kind;
      p.centre = m->centre(t_fire, scene.terrain).cast<float>();
      p.half = 0.5f * m->size;
      p.setYaw(float(m->yaw()));
      p.reflectivity = m->reflectivity;
      boxes.push_back(p);
      box_instance.push_back(m->instance);
    }
    std::vector<LidarPoint>& out = per_column[c];
    out.reserve(B);
    const double ca = std::cos(azimuth), sa = std::sin(azimuth);
    for (int b = 0; b < B; ++b) {
      const uint64_t key =
          hashOf(options.seed, kStreamRay, uint64_t(scan), uint64_t(b), uint64_t(c));
      const Eigen::Vector3d d_S(cos_el[b] * ca, cos_el[b] * sa, sin_el[b]);
      const Eigen::Vector3d d = T.linear() * d_S;
      double t_hit = sensor.max_range;
      bool hit = false;
      Kind kind = Kind::kVoid;
      uint32_t instance = 0, object = 0;
      float reflect = 0.0f, cos_inc = 1.0f;
      bool porous = false;
      // The ground march and the object grid walk are the costly parts; each stops at the
      // other's hit. Rays going down meet the ground first more often, rays going up objects.
      const float grass_fraction = float(unitOf(hashOf(key, 1)));
      auto castObjects = [&] {
        ObjectHit oh;
        if (!scene.object_grid.cast(o, d, t_hit, key, &oh)) return;
        const Primitive& p = scene.objects[oh.index];
        hit = true;
        t_hit = oh.t;
        kind = p.kind;
        object = p.id;
        reflect = p.reflectivity;
        porous = oh.porous;
        cos_inc = float(std::abs(d.cast<float>().dot(oh.normal)));
      };
      auto castGround = [&] {
        double t;
        if (!scene.terrain.march(o, d, t_hit, grass_fraction, &t)) return;
        const Eigen::Vector3d p = o + t * d;
        hit = true;
        t_hit = t;
        kind = scene.terrain.kindAt(p.x(), p.y());
        reflect = kindInfo(kind).reflectivity;
        object = 0;
        // Grass blades have random orientations.
        porous = scene.terrain.grassHeight(p.x(), p.y()) > 0.03f;
        cos_inc = float(std::abs(d.dot(scene.terrain.normal(p.x(), p.y()).cast<double>())));
      };
      if (d.z() < 0.0) {
        castGround();
        castObjects();
      } else {
        castObjects();
        castGround();
      }
      for (size_t k = 0; k < boxes.size(); ++k) {
        double t0, t1;
        Eigen::Vector3f n;
        if (boxes[k].intersect(o, d, t_hit, &t0, &t1, &n) && t0 > 0.0 && t0 < t_hit) {
          hit = true;
          t_hit = t0;
          kind = boxes[k].kind;
          instance = box_instance[k];
          object = kMoverObject + instance;
          reflect = boxes[k].reflectivity;
          porous = false;
          cos_inc = float(std::abs(d.cast<float>().dot(n)));
        }
      }
      if (!hit) continue;
      if (porous) cos_inc = float(0.25 + 0.75 * unitOf(hashOf(key, 2)));
      // Dropouts: specular water, grazing incidence, weak echoes far away.
      const double u_drop = unitOf(hashOf(key, kStreamDropout));
      if (kind == Kind::kPuddle) {
        const double c2 = double(cos_inc) * cos_inc, c8 = c2 * c2 * c2 * c2;
        if (u_drop > 0.02 + 0.9 * c8) continue;
      } else if (!porous) {
        if (u_drop > std::clamp((cos_inc - 0.008) / 0.035, 0.0, 1.0)) continue;
      }
      const double echo = reflect * (0.5 + 0.5 * cos_inc);
      const double reach =
          sensor.range_10pct * std::sqrt(echo / 0.1) * (1.0 + 0.08 * normalOf(hashOf(key, 3)));
      if (t_hit > reach) continue;
      const double range = t_hit + sensor.range_sigma * normalOf(hashOf(key, kStreamNoise));
      if (range < sensor.min_range || range > sensor.max_range) continue;
      const Eigen::Vector3d p_W = o + range * d;
      LidarPoint lp;
      lp.p_W = p_W.cast<float>();
      lp.p_S = (T_end_inv * p_W).cast<float>();
      lp.remission = float(std::clamp(
          reflect * (0.3 + 0.7 * cos_inc) * (1.0 + 0.1 * normalOf(hashOf(key, kStreamRemission))),
          0.0, 1.0));
      lp.range = float(range);
      lp.height = float(p_W.z() - scene.terrain.groundHeight(p_W.x(), p_W.y()));
      lp.kind = kind;
      lp.instance = instance;
      lp.object = object;
      lp.beam = uint16_t(b);
      lp.column = uint16_t(c);
      out.push_back(lp);
    }
  }
  size_t total = 0;
  for (const auto& col : per_column) total += col.size();
  std::vector<LidarPoint> points;
  points.reserve(total);
  for (const auto& col : per_column) points.insert(points.end(), col.begin(), col.end());
  return points;
}

}  // namespace evidential_octomap::generator
