// Spinning LiDAR models and the casting of one sweep.
//   hdl-64   Velodyne HDL-64E-like: 64 beams, +2.0 .. -8.33 deg (1/3 deg) and -8.87 .. -24.9 deg,
//            2048 columns by default, 120 m, range noise 2 cm
//   os1-32, os1-64, os1-128  Ouster OS1-like: uniform beams over +-22.5 deg, 1024 columns by
//            default, 120 m, range noise 2.5 cm
// Per return: range noise (Gaussian), dropouts on water (specular: almost nothing comes back
// except near normal incidence), at grazing incidence and beyond the range at which the target's
// reflectivity still gives a detectable echo; remission from the class's reflectivity and the
// incidence angle. With motion distortion every column is cast from the pose at its firing time
// and stored in the end-of-sweep sensor frame, as a raw driver delivers it.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "kinds.h"

namespace evidential_octomap::generator {

struct Scene;
struct Mover;
class Trajectory;

struct SensorModel {
  std::string name;
  std::vector<double> elevation_deg;  // per beam, top to bottom
  int columns = 1024;
  double max_range = 120.0, min_range = 1.0;
  double range_sigma = 0.025;  // [m]
  double range_10pct = 50.0;   // detection range of a 10 % Lambertian target [m]
  double rate_hz = 10.0;

  int beams() const { return int(elevation_deg.size()); }
  // Geometric mean of the vertical and horizontal angular spacing [rad]: point spacing per metre.
  double angularSpacing() const;
  // hdl-64, os1-32, os1-64, os1-128; columns 0: the sensor's default. Throws on unknown names.
  static SensorModel make(const std::string& name, int columns, double range_sigma);
};

struct LidarPoint {
  Eigen::Vector3f p_S;  // measured point, end-of-sweep sensor frame
  Eigen::Vector3f p_W;  // the same point in the world frame
  float remission;
  float range;   // measured range [m]
  float height;  // above the ground under it [m]
  Kind kind;
  uint32_t instance;  // mover instance (0: static)
  uint32_t object;    // static object id, 0x10000 + instance for movers, 0 ground
  uint16_t beam, column;
};

struct CastOptions {
  bool motion_distortion = false;
  uint64_t seed = 0;
};

// Sweep `scan` ending at t_end; T_end is the end-of-sweep pose (written to poses.txt).
std::vector<LidarPoint> castScan(const Scene& scene, const Trajectory& trajectory,
                                 const std::vector<Mover>& movers, const SensorModel& sensor,
                                 int scan, double t_end, const CastOptions& options,
                                 const Eigen::Isometry3d& T_end);

}  // namespace evidential_octomap::generator
