// Where class borders are: for every 0.5 m cell and class, the xy distance to the nearest
// ground cell of that class and, separately, to the nearest footprint of an object of that class
// (capped at 2.5 m). The network model confuses a point with the nearest other class when it is
// close: a ground point with the ground and objects around it, an object point with the objects
// around it (and with the ground below it, by its height).
#pragma once

#include <cstdint>
#include <vector>

#include "grid2.h"
#include "kinds.h"
#include "primitives.h"

namespace evidential_octomap::generator {

class Terrain;

class BorderMap {
 public:
  static constexpr float kCap = 2.5f;
  static constexpr double kResolution = 0.5;
  void build(const Terrain& terrain, const std::vector<Primitive>& objects,
             const KindClasses& classes, int num_classes);
  // Nearest class other than `cls` at (x, y) and its distance (kCap and -1 when none is near);
  // `with_ground`: the ground layer counts too.
  float nearestOther(double x, double y, int cls, bool with_ground, int* other) const;

 private:
  Grid2 grid_;
  int C_ = 0;
  std::vector<uint8_t> dist_[2];  // ground, objects: per cell, C distances in decimetres
};

}  // namespace evidential_octomap::generator
