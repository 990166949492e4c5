// Static objects as primitives (vertical or lying cylinders, ellipsoids, boxes; each with a yaw)
// and a 2-D uniform grid over them for ray casting. Foliage (canopies, bushes) is porous: a ray
// entering it travels an exponentially distributed free path (density per metre, drawn from a
// hash of the ray and the object) and passes through when that path is longer than its chord.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "grid2.h"
#include "kinds.h"

namespace evidential_octomap::generator {

enum class Shape : uint8_t { kCylinderZ, kCylinderX, kEllipsoid, kBox };

struct Primitive {
  Shape shape;
  Kind kind;
  float density = 0.0f;  // porous foliage: returns per metre of chord (0: solid)
  Eigen::Vector3f centre;
  Eigen::Vector3f half;  // half extents in the object frame (cylinder: radius, radius, half length
                         // along its axis for kCylinderZ; half length, radius, radius for X)
  float yaw = 0.0f;
  float cos_yaw = 1.0f, sin_yaw = 0.0f;  // of yaw; setYaw() keeps them in step
  float bound = 0.0f;                    // bounding sphere radius; setYaw() sets it
  uint32_t id = 0;  // object id (network model's per-object correlation); index + 1
  float reflectivity = 0.3f;

  // Sets the yaw (and the cached cos, sin and bounding radius: call after setting `half`).
  void setYaw(float y);
  // Entry and exit of the ray (o, unit d) in [0, tmax]; the outward normal at entry.
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax, double* t0,
                 double* t1, Eigen::Vector3f* normal) const;
  // Bounding radius in xy and z range, for the grid.
  float radiusXY() const;
  float zmin() const;
  float zmax() const;
};

struct ObjectHit {
  double t;
  uint32_t index;  // into the primitive list
  Eigen::Vector3f normal;
  bool porous;
};

class ObjectGrid {
 public:
  static constexpr double kCell = 2.0;
  void build(const std::vector<Primitive>* prims, const Grid2& extent);
  // Nearest hit along (o, unit d) before tmax; ray_key decides the porous pass-throughs.
  bool cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax, uint64_t ray_key,
            ObjectHit* hit) const;

 private:
  const std::vector<Primitive>* prims_ = nullptr;
  Grid2 grid_;
  std::vector<uint32_t> offsets_, items_;
  std::vector<float> cell_top_;  // highest z of the cell's primitives
};

}  // namespace evidential_octomap::generator
