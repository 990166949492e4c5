// The ground: a heightfield (0.25 m cells, bilinear) with real slopes and multi-octave roughness,
// the trail or road flattened into it, puddles as flat water surfaces in carved depressions with
// mud around them, a grass layer of varying height, and the ground kind of every cell.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "grid2.h"
#include "kinds.h"

namespace evidential_octomap::generator {

struct Route;

// Distance from every 0.5 m cell to the driven part of the route (capped at kMax) and the arc
// length of the nearest route sample.
struct PathField {
  static constexpr float kMax = 30.0f;
  Grid2 grid;
  std::vector<float> dist;
  std::vector<float> arc;
  float distance(double x, double y) const { return dist[grid.cellOf(x, y)]; }
  static PathField make(const Route& route, double max_arc, const Grid2& grid);
};

struct TerrainParams {
  double grade = 0.05;          // slope of the underlying plane (rise over run)
  double hills = 2.0;           // amplitude of the 60 m undulation [m]
  double roughness = 0.05;      // amplitude of the 2 m roughness [m]
  double trail_half_width = 1.3;
  double puddles_per_100m = 1.0;     // on the trail
  double puddle_cells = 0.0;         // off-trail puddles: probability per 25 m cell
  static TerrainParams of(Family f);
};

struct Puddle {
  Eigen::Vector2d centre;
  double radius, level;
};

class Terrain {
 public:
  static constexpr double kResolution = 0.25;

  static Terrain build(Family family, uint64_t seed, const Grid2& grid, const Route& route,
                       const PathField& path);

  const Grid2& grid() const { return grid_; }
  const TerrainParams& params() const { return params_; }
  const std::vector<Puddle>& puddles() const { return puddles_; }
  // Ground (or water) surface height, without grass.
  double groundHeight(double x, double y) const;
  float grassHeight(double x, double y) const;
  Kind kindAt(double x, double y) const { return Kind(kind_[grid_.cellOf(x, y)]); }
  Eigen::Vector3f normal(double x, double y) const;
  // First crossing of the ray o + t d (t in (0, tmax]) with the surface height + grass_fraction
  // times the grass height (each ray sees the grass layer's top at its own depth: a porous
  // layer). Sphere tracing with the surface's Lipschitz bound, then bisection.
  bool march(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax,
             float grass_fraction, double* t) const;

 private:
  struct Cell {
    float h, grass;
  };
  // Bilinear h + f * grass.
  double surface(double x, double y, float grass_fraction) const;

  Grid2 grid_;
  TerrainParams params_;
  std::vector<Cell> cells_;
  std::vector<uint8_t> kind_;
  std::vector<Puddle> puddles_;
  double lipschitz_ = 1.0;
};

}  // namespace evidential_octomap::generator
