// Where class borders are: for every 0.5 m cell and class, the xy distance to the nearest
// ground cell or object footprint of that class (capped at 2.5 m). The network model confuses a
// point with the nearest other class when it is close.
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
  // Nearest class other than `cls` at (x, y) and its distance (kCap and -1 when none is near).
  float nearestOther(double x, double y, int cls, int* other) const;

 private:
  Grid2 grid_;
  int C_ = 0;
  std::vector<uint8_t> dist_;  // per cell, C distances in decimetres
};

}  // namespace evidential_octomap::generator
