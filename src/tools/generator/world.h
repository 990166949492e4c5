// Everything a sequence is generated from, built once from the options: the sensor, the route
// and trajectory, the movers and the scene (the movers come first: objects keep clear of their
// paths). Shared by `generate` and the tests, which rebuild a dataset's world to check it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "generator/agents.h"
#include "generator/kinds.h"
#include "generator/lidar.h"
#include "generator/scene.h"
#include "generator/trajectory.h"

namespace evidential_octomap::generator {

struct WorldOptions {
  Family family = Family::kForest;
  std::string sensor = "os1-64";
  int columns = 0;            // 0: the sensor's default
  double range_noise = -1.0;  // negative: the sensor's default
  double max_range = 0.0;     // 0: the sensor's default (120 m)
  int scans = 100;
  uint64_t seed = 0;
  RouteKind route = RouteKind::kLoop;
  double route_length = 400.0, speed = 2.0, sensor_height = 1.8;
  int movers = 4;
};

struct World {
  WorldOptions options;
  SensorModel sensor;
  KindClasses classes;
  Route route;
  MotionParams motion;
  std::vector<Mover> movers;
  std::unique_ptr<Scene> scene;
  std::unique_ptr<Trajectory> trajectory;
  double period = 0.1;

  // End of sweep i (the time of poses.txt line i).
  double scanTime(int i) const { return (i + 1) * period; }
  // `table` is the family's class table (classTableYaml, loaded).
  static std::unique_ptr<World> make(const WorldOptions& options, const ClassTable& table);
};

}  // namespace evidential_octomap::generator
