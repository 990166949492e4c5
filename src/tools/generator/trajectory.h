// The route the robot drives (a trail or road on the terrain) and the sensor's pose along it.
//   loop          a closed wobbly loop of `length` metres, driven round and round (revisits);
//   out-and-back  an open winding path of `length` metres, driven to its end, turned in place
//                 (skid steer) and driven back, repeatedly (revisits in the opposite direction);
//   line          an open winding path, never revisited.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

namespace evidential_octomap::generator {

class Terrain;

enum class RouteKind { kLoop, kOutAndBack, kLine };
RouteKind parseRoute(const std::string& name);  // throws std::invalid_argument
const char* routeName(RouteKind r);

struct Route {
  RouteKind kind = RouteKind::kLoop;
  std::vector<Eigen::Vector2d> xy;  // samples every `step` metres along the path
  double step = 0.5;
  double length = 0.0;  // path length [m]

  // Position and unit tangent at arc length s (clamped, or wrapped for a loop).
  Eigen::Vector2d at(double s) const;
  Eigen::Vector2d tangent(double s) const;

  static Route make(RouteKind kind, double length, uint64_t seed);
};

struct MotionParams {
  double speed = 2.0;          // [m/s]
  double sensor_height = 1.8;  // above the ground, along the body's z axis [m]
  double turn_rate = 0.8;      // in-place turn of out-and-back [rad/s]
};

// Where the robot is at time t: arc length along the route and heading (its direction of travel).
class Trajectory {
 public:
  Trajectory(const Route& route, const MotionParams& motion, const Terrain& terrain)
      : route_(route), motion_(motion), terrain_(terrain) {}

  // xy and heading [rad] at time t (t < 0: the start).
  void planar(double t, Eigen::Vector2d* xy, double* heading) const;
  // T_W_S: sensor (x forward, y left, z up) in the world, roll and pitch following the terrain.
  Eigen::Isometry3d pose(double t) const;
  // Arc length driven by time t, and the part of the route [0, s_max] visited up to time t.
  double distanceDriven(double t) const { return t <= 0.0 ? 0.0 : t * motion_.speed; }
  double maxArcLength(double t) const;

 private:
  const Route& route_;
  MotionParams motion_;
  const Terrain& terrain_;
};

}  // namespace evidential_octomap::generator
