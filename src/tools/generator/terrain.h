// The ground: a heightfield (0.25 m cells, bilinear) with real slopes and multi-octave roughness,
// the trail or road flattened into it, puddles as flat water surfaces in carved depressions with
// mud around them, a grass layer of varying height, and the ground kind of every cell.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "grid2.h"
#include "kinds.h"

namespace evidential_octomap::generator {

struct Route;

// Distance from every 0.5 m cell to the route's arc range [a0, a1] (the part driven and some
// way beyond; capped at kMax) and the arc length of the nearest route sample (in [0, length)).
struct PathField {
  static constexpr float kMax = 30.0f;
  Grid2 grid;
  std::vector<float> dist;
  std::vector<float> arc;
  float distance(double x, double y) const { return dist[grid.cellOf(x, y)]; }
  double a0 = 0.0, a1 = 0.0;
  static PathField make(const Route& route, double a0, double a1, const Grid2& grid);
};

struct TerrainParams {
  double grade = 0.05;      // slope of the underlying plane (rise over run)
  double hills = 2.0;       // amplitude of the 60 m undulation [m]
  double roughness = 0.05;  // amplitude of the 2 m roughness [m]
  double trail_half_width = 1.3;
  double puddles_per_100m = 1.0;  // on the trail
  double puddle_cells = 0.0;      // off-trail puddles: probability per 25 m cell
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
  // layer). Sphere tracing with local Lipschitz bounds, then bisection.
  bool march(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax, float grass_fraction,
             double* t) const;

 private:
  struct Cell {
    float h, grass;
  };
  // Bilinear h + f * grass.
  double surface(double x, double y, float grass_fraction) const;

  static constexpr int kTileCells = 16;  // 4 m tiles of the marcher's local bounds
  size_t tileOf(double x, double y) const {
    const int tx = grid_.ix(x) / kTileCells, ty = grid_.iy(y) / kTileCells;
    return size_t(ty) * size_t(tiles_x_) + size_t(tx);
  }

  Grid2 grid_;
  TerrainParams params_;
  std::vector<Cell> cells_;
  std::vector<uint8_t> kind_;
  std::vector<Puddle> puddles_;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<float> tile_slope_, tile_top_;
  double top_ = -1e30;  // highest surface of all
};

}  // namespace evidential_octomap::generator
