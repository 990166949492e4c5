#include "agents.h"

#include <algorithm>
#include <cmath>

#include "rng.h"
#include "terrain.h"
#include "trajectory.h"

namespace evidential_octomap::generator {

Eigen::Vector3d Mover::centre(double t, const Terrain& terrain) const {
  const double s = std::clamp((t - t_start) * speed, 0.0, length);
  const Eigen::Vector2d p = start + s * dir;
  return {p.x(), p.y(), terrain.groundHeight(p.x(), p.y()) + 0.5 * size.z()};
}

double Mover::yaw() const { return std::atan2(dir.y(), dir.x()); }

double Mover::distanceToPath(const Eigen::Vector2d& xy) const {
  const double s = std::clamp((xy - start).dot(dir), 0.0, length);
  return (xy - (start + s * dir)).norm();
}

std::vector<Mover> makeMovers(int count, double duration, const Trajectory& trajectory,
                              uint64_t seed) {
  std::vector<Mover> movers;
  const uint64_t key = hashOf(seed, kStreamMovers);
  for (int m = 0; m < count; ++m) {
    const uint64_t h = hashOf(key, uint64_t(m));
    Mover a;
    a.instance = uint32_t(m + 1);
    const bool person = unitOf(hashOf(h, 1)) < 0.55;
    a.kind = person ? Kind::kPerson : Kind::kVehicle;
    a.speed = person ? 1.1 + 0.5 * unitOf(hashOf(h, 2)) : 4.0 + 4.0 * unitOf(hashOf(h, 2));
    a.size = person ? Eigen::Vector3f(0.6f, 0.6f, 1.7f + 0.2f * float(unitOf(hashOf(h, 3))))
                    : Eigen::Vector3f(4.5f, 1.9f, 1.6f);
    a.reflectivity = person ? 0.25f + 0.2f * float(unitOf(hashOf(h, 4)))
                            : 0.2f + 0.6f * float(unitOf(hashOf(h, 4)));  // dark to white paint
    // The crossing: the mover passes a point `ahead` metres in front of where the robot is at
    // t_cross (the robot reaches it several seconds later), at 50-130 degrees to the route.
    const double t_cross = duration * (m + 0.3 + 0.4 * unitOf(hashOf(h, 5))) / std::max(count, 1);
    const double ahead = 12.0 + 18.0 * unitOf(hashOf(h, 6));
    Eigen::Vector2d xy;
    double heading;
    trajectory.planar(t_cross, &xy, &heading);
    const Eigen::Vector2d f(std::cos(heading), std::sin(heading));
    const Eigen::Vector2d cross = xy + ahead * f;
    const double angle =
        (unitOf(hashOf(h, 7)) < 0.5 ? 1.0 : -1.0) * (0.87 + 1.4 * unitOf(hashOf(h, 8)));
    const double dir_heading = heading + angle;
    a.dir = Eigen::Vector2d(std::cos(dir_heading), std::sin(dir_heading));
    const double half = person ? 25.0 : 70.0;
    a.length = 2.0 * half;
    a.start = cross - half * a.dir;
    a.t_start = t_cross - half / a.speed;
    movers.push_back(a);
  }
  return movers;
}

}  // namespace evidential_octomap::generator
