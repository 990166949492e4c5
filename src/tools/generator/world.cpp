#include "generator/world.h"

#include <algorithm>
#include <stdexcept>

#include "generator/rng.h"

namespace evidential_octomap::generator {

std::unique_ptr<World> World::make(const WorldOptions& o, const ClassTable& table) {
  if (o.scans < 1) throw std::invalid_argument("--scans must be at least 1");
  if (o.speed < 0.0) throw std::invalid_argument("--speed must not be negative");
  auto w = std::make_unique<World>();
  w->options = o;
  w->sensor = SensorModel::make(o.sensor, o.columns, o.range_noise);
  if (o.max_range > 0.0) w->sensor.max_range = std::max(o.max_range, w->sensor.min_range + 1.0);
  w->classes = KindClasses::of(table);
  w->period = 1.0 / w->sensor.rate_hz;
  const double duration = o.scans * w->period;
  double length = o.route_length;
  if (o.route == RouteKind::kLine) length = std::max(length, o.speed * duration + 10.0);
  // The family is part of the world's seed: two families of one seed share no route or movers.
  const uint64_t seed = hashOf(o.seed, uint64_t(o.family));
  w->route = Route::make(o.route, length, seed);
  w->motion.speed = o.speed;
  w->motion.sensor_height = o.sensor_height;
  // The movers need only the planar trajectory, which does not read the terrain.
  const Terrain no_terrain;
  const Trajectory planar(w->route, w->motion, no_terrain);
  w->movers = makeMovers(o.movers, duration, planar, seed);
  const double max_arc = planar.maxArcLength(duration) + 5.0;
  w->scene = Scene::build(o.family, seed, w->route, max_arc,
                          std::min(w->sensor.max_range, 100.0) + 5.0, w->movers, w->classes);
  w->trajectory = std::make_unique<Trajectory>(w->route, w->motion, w->scene->terrain);
  return w;
}

}  // namespace evidential_octomap::generator
