// Moving agents: people walking and vehicles driving along straight paths that cross the route
// a few tens of metres ahead of the robot, so they cross the sensor's view; each appears at its
// path's start, walks or drives to its end and leaves the scene there. Boxes with a yaw.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "kinds.h"

namespace evidential_octomap::generator {

class Terrain;
class Trajectory;

struct Mover {
  uint32_t instance;           // 1, 2, ... (upper 16 bits of labels/)
  Kind kind;                   // kPerson or kVehicle
  Eigen::Vector2d start, dir;  // path start and unit direction
  double speed, length;        // [m/s], path length [m]
  double t_start;              // time at the path's start [s]
  Eigen::Vector3f size;        // box length, width, height [m]
  float reflectivity;

  double tEnd() const { return t_start + length / speed; }
  bool present(double t) const { return t >= t_start && t <= tEnd(); }
  // Box centre (on the terrain) and yaw at time t.
  Eigen::Vector3d centre(double t, const Terrain& terrain) const;
  double yaw() const;
  // Distance from xy to the path segment (objects are kept clear of it).
  double distanceToPath(const Eigen::Vector2d& xy) const;
};

// `count` movers over a sequence of `duration` seconds, about one person in two.
std::vector<Mover> makeMovers(int count, double duration, const Trajectory& trajectory,
                              uint64_t seed);

}  // namespace evidential_octomap::generator
