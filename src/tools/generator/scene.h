// A procedural off-road world from a seed: terrain (terrain.h), static objects (primitives.h)
// placed by family on a jittered grid clear of the route and the movers' paths, and the
// border map the network model reads.
//   forest     trail; trees (trunk + porous canopy), bushes, logs; grass and dirt floor; puddles
//   grassland  track; tall grass, puddles and mud in depressions, few bushes
//   rocky      a 15-30 % slope; boulders, rocks, gravel, some bushes and trees
//   farm       dirt road; fences (posts + rails), utility poles, buildings with concrete slabs,
//              parked vehicles, trees, bushes, grass
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "agents.h"
#include "border_map.h"
#include "primitives.h"
#include "terrain.h"
#include "trajectory.h"

namespace evidential_octomap::generator {

struct Scene {
  Family family;
  uint64_t seed;
  Grid2 extent;
  PathField path;
  Terrain terrain;
  std::vector<Primitive> objects;
  ObjectGrid object_grid;
  BorderMap borders;

  // The part of the world within `margin` metres of the route's first `max_arc` metres.
  // Built in place (the object grid points into `objects`).
  static std::unique_ptr<Scene> build(Family family, uint64_t seed, const Route& route,
                                      double max_arc, double margin,
                                      const std::vector<Mover>& movers, const KindClasses& classes);
};

}  // namespace evidential_octomap::generator
