// A SYNTHETIC scene with known ground truth (voxblox simulation_world / nvblox primitives style):
// a flat ground of class 0 and a box of class 1, ray-cast from a sensor above the ground.
// Every point is the first intersection of a ray with the ground or the box; its evidence is
// drawn around its true class with noise, and a fraction of points get evidence for a wrong class.
// Surfaces sit in the middle of voxel layers at resolution 0.2 m, so no point lands on a boundary.
#pragma once

#include <octomap/octomap.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace evidential_octomap {
namespace test {

struct SyntheticScan {
  octomap::Pointcloud points_W;
  std::vector<float> evidence;  // N x C
  std::vector<int> labels;      // true class per point
  octomap::point3d origin_W;
};

struct SyntheticScene {
  static constexpr int kGround = 0;
  static constexpr int kBox = 1;

  int num_classes = 3;
  float ground_z = 0.1f;
  octomap::point3d box_min{3.1f, -0.9f, 0.1f};
  octomap::point3d box_max{4.1f, 0.9f, 1.5f};
  double azimuth_step_deg = 1.0;    // rays over azimuth -40 .. 40 deg
  double elevation_step_deg = 1.0;  // and elevation -45 .. -8 deg (ground hits 1.7 .. 12 m)
  double wrong_fraction = 0.05;     // points whose evidence favours a wrong class
  double true_evidence = 3.0;       // true class gets true_evidence + U(0, true_evidence)
  double noise_evidence = 0.6;      // every class gets U(0, noise_evidence)

  // Distance along the unit ray (o, d) to the box, or +inf (slab test).
  float hitBox(const octomap::point3d& o, const octomap::point3d& d) const {
    float t_near = -std::numeric_limits<float>::infinity();
    float t_far = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (std::fabs(d(a)) < 1e-9f) {
        if (o(a) < box_min(a) || o(a) > box_max(a)) return std::numeric_limits<float>::infinity();
        continue;
      }
      float t0 = (box_min(a) - o(a)) / d(a), t1 = (box_max(a) - o(a)) / d(a);
      if (t0 > t1) std::swap(t0, t1);
      t_near = std::max(t_near, t0);
      t_far = std::min(t_far, t1);
    }
    if (t_near > t_far || t_near <= 0.0f) return std::numeric_limits<float>::infinity();
    return t_near;
  }

  // One scan from `origin_W`; the same seed gives the same scan.
  SyntheticScan scan(const octomap::point3d& origin_W, unsigned seed) const {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    SyntheticScan out;
    out.origin_W = origin_W;
    const double deg = 3.14159265358979323846 / 180.0;
    for (double az = -40.0; az <= 40.0 + 1e-9; az += azimuth_step_deg) {
      for (double el = -45.0; el <= -8.0 + 1e-9; el += elevation_step_deg) {
        const octomap::point3d d(float(std::cos(el * deg) * std::cos(az * deg)),
                                 float(std::cos(el * deg) * std::sin(az * deg)),
                                 float(std::sin(el * deg)));
        const float t_ground = (ground_z - origin_W.z()) / d.z();
        const float t_box = hitBox(origin_W, d);
        const int label = t_box < t_ground ? kBox : kGround;
        const float t = std::min(t_box, t_ground);
        out.points_W.push_back(origin_W + d * t);
        out.labels.push_back(label);
        int favoured = label;
        if (unit(rng) < wrong_fraction) {
          favoured = (label + 1 + int(unit(rng) * (num_classes - 1))) % num_classes;
        }
        for (int c = 0; c < num_classes; ++c) {
          double e = unit(rng) * noise_evidence;
          if (c == favoured) e += true_evidence * (1.0 + unit(rng));
          out.evidence.push_back(static_cast<float>(e));
        }
      }
    }
    return out;
  }

  SyntheticScan defaultScan(unsigned seed = 1) const {
    return scan(octomap::point3d(0.05f, 0.1f, 1.7f), seed);
  }
};

}  // namespace test
}  // namespace evidential_octomap
