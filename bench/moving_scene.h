// SYNTHETIC street scenes with movers for bench/moving_street.cpp: a road (z = 0.1 m), a
// facade 20 m ahead, a pole and a parked car that occlude, and people and vehicles as boxes on
// straight paths, seen by a static 32-beam LiDAR at 1.8 m (elevation -22.5 .. +22.5 deg, azimuth
// -60 .. 60 deg in 0.2 deg). Every return gets Gaussian range noise (2 cm) and the evidence of a
// noisy network: the true class's evidence is drawn in 2 .. 12, every other class gets a little,
// and 5 % of the points (10 % on a mover's edge) are labelled as another class. Bench-only.
#pragma once

#include <octomap/Pointcloud.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace moving_scene {

enum Class : int { kRoad = 0, kPerson = 1, kCar = 2, kBuilding = 3, kPole = 4, kClasses = 5 };
inline const char* className(int c) {
  static const char* names[] = {"road", "person", "car", "building", "pole"};
  return c >= 0 && c < kClasses ? names[c] : "none";
}
constexpr float kRoadZ = 0.1f, kFacadeX = 20.1f, kMaxRange = 30.0f;

// An axis-aligned box: a static object, or a mover at one scan.
struct Box {
  octomap::point3d min, max;
  int label;
  bool contains(const octomap::point3d& p) const {
    for (int a = 0; a < 3; ++a)
      if (p(a) < min(a) || p(a) > max(a)) return false;
    return true;
  }
  // Entry distance of the ray (o, d) (d unit), +inf when it misses.
  float entry(const octomap::point3d& o, const octomap::point3d& d) const {
    float t_near = 0.0f, t_far = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (std::fabs(d(a)) < 1e-9f) {
        if (o(a) < min(a) || o(a) > max(a)) return std::numeric_limits<float>::infinity();
        continue;
      }
      float t0 = (min(a) - o(a)) / d(a), t1 = (max(a) - o(a)) / d(a);
      if (t0 > t1) std::swap(t0, t1);
      t_near = std::max(t_near, t0), t_far = std::min(t_far, t1);
    }
    return t_near <= t_far ? t_near : std::numeric_limits<float>::infinity();
  }
};

// A box of size (sx, sy, sz) standing on the road, moving from (x0, y0) to (x1, y1) during scans
// [first, last].
struct Mover {
  std::string name;
  int label;
  octomap::point3d size;
  float x0, y0, x1, y1;
  int first, last;
  bool present(int scan) const { return scan >= first && scan <= last; }
  Box at(int scan) const {
    const float s = last > first ? float(scan - first) / float(last - first) : 0.0f;
    const float x = x0 + s * (x1 - x0), y = y0 + s * (y1 - y0);
    return {octomap::point3d(x - size.x() / 2, y - size.y() / 2, kRoadZ),
            octomap::point3d(x + size.x() / 2, y + size.y() / 2, kRoadZ + size.z()), label};
  }
};

inline Mover person(const std::string& name, float x0, float y0, float x1, float y1, int first,
                    int last) {
  return {name, kPerson, octomap::point3d(0.6f, 0.6f, 1.8f), x0, y0, x1, y1, first, last};
}
inline Mover car(const std::string& name, float x0, float y0, float x1, float y1, int first,
                 int last) {  // driving along y: 4.5 m long on y
  return {name, kCar, octomap::point3d(1.8f, 4.5f, 1.5f), x0, y0, x1, y1, first, last};
}

struct Case {
  std::string name;
  std::vector<Mover> movers;
  int scans;  // movers, then empty street
};

// The cases: the walking person of the user's report, a car driving past, people walking toward
// and away from the sensor, and several movers at once. Each ends 20 scans after its last mover
// left, a person walks 1.5 m/s and a car 5 m/s at 10 scans/s.
inline std::vector<Case> cases() {
  return {
      {"person crossing 8 m away", {person("person", 8.0f, -7.5f, 8.0f, 7.5f, 0, 99)}, 160},
      {"car driving past 10 m away", {car("car", 10.0f, -16.0f, 10.0f, 16.0f, 0, 63)}, 84},
      {"person walking toward the sensor", {person("person", 17.0f, 1.0f, 3.0f, 1.0f, 0, 93)}, 114},
      {"person walking away", {person("person", 3.0f, -1.5f, 17.0f, -1.5f, 0, 93)}, 114},
      {"two people and a car at once",
       {person("person A", 7.0f, 6.0f, 7.0f, -6.0f, 0, 79),
        person("person B", 15.0f, 3.0f, 5.0f, 3.0f, 5, 71),
        car("car", 11.5f, -16.0f, 11.5f, 16.0f, 10, 73)},
       94},
  };
}

// Static objects off the movers' paths: a pole and a parked car.
inline std::vector<Box> staticBoxes() {
  return {{octomap::point3d(5.0f, -5.1f, kRoadZ), octomap::point3d(5.2f, -4.9f, 3.0f), kPole},
          {octomap::point3d(14.0f, 6.5f, kRoadZ), octomap::point3d(15.8f, 11.0f, 1.6f), kCar}};
}

struct Sensor {
  octomap::point3d origin{0.0f, 0.0f, 1.8f};
  std::mt19937 rng{7};

  // One scan of the street with the movers present at `scan`: points (world frame) and
  // evidence (points x kClasses).
  void scan(const Case& c, int index, octomap::Pointcloud* points, std::vector<float>* evidence) {
    points->clear();
    evidence->clear();
    std::vector<Box> boxes = staticBoxes();
    const size_t statics = boxes.size();
    for (const Mover& m : c.movers)
      if (m.present(index)) boxes.push_back(m.at(index));
    std::normal_distribution<float> noise(0.0f, 0.02f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int beam = 0; beam < 32; ++beam) {
      const double elevation = (-22.5 + 45.0 * beam / 31.0) * M_PI / 180.0;
      for (double azimuth = -60.0; azimuth <= 60.0; azimuth += 0.2) {
        const double a = azimuth * M_PI / 180.0;
        const octomap::point3d d(std::cos(elevation) * std::cos(a),
                                 std::cos(elevation) * std::sin(a), std::sin(elevation));
        float best = std::numeric_limits<float>::infinity();
        int label = -1;
        bool edge = false;
        if (d.z() < 0.0f) best = (kRoadZ - origin.z()) / d.z(), label = kRoad;
        if (d.x() > 0.0f && (kFacadeX - origin.x()) / d.x() < best)
          best = (kFacadeX - origin.x()) / d.x(), label = kBuilding;
        for (size_t b = 0; b < boxes.size(); ++b) {
          const float t = boxes[b].entry(origin, d);
          if (t < best) best = t, label = boxes[b].label, edge = b >= statics && nearEdge(boxes[b], origin + d * t);
        }
        if (!(best < kMaxRange)) continue;
        points->push_back(origin + d * (best + noise(rng)));
        const int shown = unit(rng) < (edge ? 0.10f : 0.05f) ? otherClass(label) : label;
        for (int k = 0; k < kClasses; ++k)
          evidence->push_back(k == shown ? 2.0f + 10.0f * unit(rng) : 0.3f * unit(rng));
      }
    }
  }

 private:
  static bool nearEdge(const Box& b, const octomap::point3d& p) {
    for (int a = 0; a < 2; ++a)
      if (p(a) - b.min(a) < 0.1f || b.max(a) - p(a) < 0.1f) return true;
    return p.z() - b.min.z() < 0.15f;
  }
  int otherClass(int label) {
    const int k = std::uniform_int_distribution<int>(1, kClasses - 1)(rng);
    return (label + k) % kClasses;
  }
};

}  // namespace moving_scene
