#include "terrain.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "noise.h"
#include "rng.h"
#include "trajectory.h"

namespace evidential_octomap::generator {

PathField PathField::make(const Route& route, double a0, double a1, const Grid2& grid) {
  PathField f;
  f.grid = grid;
  f.a0 = a0;
  f.a1 = a1;
  f.dist.assign(grid.size(), kMax);
  f.arc.assign(grid.size(), 0.0f);
  const int r = int(std::ceil(kMax / grid.res));
  // Every sample stamps a disk; samples are in order, so ties go to the first (deterministic).
  for (double a = a0; a <= a1; a += route.step) {
    const Eigen::Vector2d p = route.at(a);
    double arc = route.kind == RouteKind::kLoop ? std::fmod(a, route.length) : a;
    if (arc < 0.0) arc += route.length;
    if (p.x() < grid.x0 - kMax || p.y() < grid.y0 - kMax ||
        p.x() > grid.x0 + grid.nx * grid.res + kMax ||
        p.y() > grid.y0 + grid.ny * grid.res + kMax) {
      continue;
    }
    const int ci = grid.ix(p.x()), cj = grid.iy(p.y());
    for (int j = std::max(0, cj - r); j <= std::min(grid.ny - 1, cj + r); ++j) {
      for (int i = std::max(0, ci - r); i <= std::min(grid.nx - 1, ci + r); ++i) {
        const double dx = grid.cx(i) - p.x(), dy = grid.cy(j) - p.y();
        const float d = float(std::sqrt(dx * dx + dy * dy));
        const size_t c = grid.index(i, j);
        if (d < f.dist[c]) {
          f.dist[c] = d;
          f.arc[c] = float(arc);
        }
      }
    }
  }
  return f;
}

TerrainParams TerrainParams::of(Family f) {
  TerrainParams p;
  switch (f) {
    case Family::kForest:
      p.grade = 0.06, p.hills = 2.5, p.roughness = 0.06, p.trail_half_width = 1.3;
      p.puddles_per_100m = 1.5, p.puddle_cells = 0.0;
      break;
    case Family::kGrassland:
      p.grade = 0.04, p.hills = 1.5, p.roughness = 0.04, p.trail_half_width = 1.5;
      p.puddles_per_100m = 2.5, p.puddle_cells = 0.35;
      break;
    case Family::kRocky:
      p.grade = 0.22, p.hills = 4.0, p.roughness = 0.12, p.trail_half_width = 1.5;
      p.puddles_per_100m = 0.0, p.puddle_cells = 0.0;
      break;
    case Family::kFarm:
      p.grade = 0.02, p.hills = 1.0, p.roughness = 0.03, p.trail_half_width = 2.0;
      p.puddles_per_100m = 1.0, p.puddle_cells = 0.05;
      break;
  }
  return p;
}

namespace {

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// Ground kind off the trail, and the grass height there. Grass heights fade in over a band of
// the mask so that the surface stays Lipschitz (the ray marcher's step depends on it).
void groundOf(Family family, uint64_t key, double x, double y, Kind* kind, float* grass) {
  const float a = fbm2(hashOf(key, 11), x, y, 25.0, 3);
  const float b = fbm2(hashOf(key, 12), x, y, 12.0, 2);
  const float tall = 0.5f + 0.5f * fbm2(hashOf(key, 13), x, y, 8.0, 2);
  auto fade = [](float v, float e0, float e1) { return float(smoothstep(e0, e1, v)); };
  switch (family) {
    case Family::kForest:  // forest floor: grass in the lighter patches, bare dirt elsewhere
      *kind = a > -0.05f ? Kind::kGrass : Kind::kDirt;
      *grass = (0.08f + 0.3f * tall) * fade(a, -0.05f, 0.15f);
      break;
    case Family::kGrassland:
      *kind = a < -0.45f ? Kind::kMud : Kind::kGrass;
      *grass = (0.15f + 0.45f * tall) * fade(a, -0.45f, -0.25f);
      break;
    case Family::kRocky:
      *kind = b > 0.25f ? Kind::kGrass : (a > -0.1f ? Kind::kGravel : Kind::kDirt);
      *grass = (0.05f + 0.2f * tall) * fade(b, 0.25f, 0.4f);
      break;
    case Family::kFarm:
      *kind = b < -0.5f ? Kind::kDirt : Kind::kGrass;
      *grass = (0.1f + 0.35f * tall) * fade(b, -0.5f, -0.3f);
      break;
  }
}

}  // namespace

Terrain Terrain::build(Family family, uint64_t seed, const Grid2& grid, const Route& route,
                       const PathField& path) {
  Terrain T;
  T.grid_ = grid;
  T.params_ = TerrainParams::of(family);
  const TerrainParams& P = T.params_;
  const uint64_t key = hashOf(seed, kStreamTerrain);
  const double dir = 6.283185307179586 * unitOf(hashOf(key, 1));
  const double gx = P.grade * std::cos(dir), gy = P.grade * std::sin(dir);
  auto base = [&](double x, double y) {
    return gx * x + gy * y + P.hills * fbm2(hashOf(key, 2), x, y, 60.0, 3) +
           P.roughness * fbm2(hashOf(key, 3), x, y, 2.0, 3);
  };

  // Trail profile: the base height smoothed over +-6 m of route, so the trail has the hills'
  // slope but not their roughness.
  std::vector<float> profile(route.xy.size());
  const int half = int(6.0 / route.step);
  for (size_t k = 0; k < route.xy.size(); ++k) {
    double sum = 0.0;
    int n = 0;
    for (int o = -half; o <= half; o += 2) {
      const double s = double(k) * route.step + o * route.step;
      const Eigen::Vector2d q = route.at(s);
      sum += gx * q.x() + gy * q.y() + P.hills * fbm2(hashOf(key, 2), q.x(), q.y(), 60.0, 3);
      ++n;
    }
    profile[k] = float(sum / n);
  }

  // Puddles: on the trail (in the ruts) and, for some families, in off-trail depressions.
  if (P.puddles_per_100m > 0.0) {
    // On a 25 m lattice of arc length, so a longer run keeps the shorter run's puddles.
    for (double s = 25.0 * std::floor(path.a0 / 25.0) + 10.0; s < path.a1; s += 25.0) {
      const uint64_t h = hashOf(key, 4, uint64_t(int64_t(std::floor(s))));
      if (unitOf(h) > P.puddles_per_100m / 4.0) continue;
      const Eigen::Vector2d t = route.tangent(s), n(-t.y(), t.x());
      const double lateral = (unitOf(hashOf(h, 1)) - 0.5) * 1.6;
      const Eigen::Vector2d c = route.at(s + 20.0 * unitOf(hashOf(h, 2))) + lateral * n;
      T.puddles_.push_back({c, 0.8 + 1.4 * unitOf(hashOf(h, 3)), 0.0});
    }
  }
  if (P.puddle_cells > 0.0) {
    const double cell = 25.0;
    for (int j = int(std::floor(grid.y0 / cell)); j * cell < grid.y0 + grid.ny * grid.res; ++j) {
      for (int i = int(std::floor(grid.x0 / cell)); i * cell < grid.x0 + grid.nx * grid.res; ++i) {
        const uint64_t h = hashOf(key, 5, uint64_t(i), uint64_t(j));
        if (unitOf(h) > P.puddle_cells) continue;
        const Eigen::Vector2d c((i + unitOf(hashOf(h, 1))) * cell,
                                (j + unitOf(hashOf(h, 2))) * cell);
        T.puddles_.push_back({c, 1.5 + 3.5 * unitOf(hashOf(h, 3)), 0.0});
      }
    }
  }

  T.cells_.resize(grid.size());
  T.kind_.resize(grid.size());
  const double trail_w = P.trail_half_width;
  const Kind trail_kind = Kind::kDirt;
#pragma omp parallel for schedule(static)
  for (int j = 0; j < grid.ny; ++j) {
    for (int i = 0; i < grid.nx; ++i) {
      const double x = grid.x0 + i * grid.res, y = grid.y0 + j * grid.res;  // cell corners
      const size_t pc = path.grid.cellOf(x, y);
      const double d = path.dist[pc];
      double h = base(x, y);
      // Flatten towards the trail profile within 2.5 m of its edge.
      const double w = 1.0 - smoothstep(trail_w, trail_w + 2.5, d);
      if (w > 0.0) {
        const size_t k = std::min(size_t(path.arc[pc] / route.step), profile.size() - 1);
        const double trail_h = profile[k] + 0.3 * P.roughness * fbm2(hashOf(key, 3), x, y, 2.0, 3);
        h = h + (trail_h - h) * w;
      }
      Kind kind = Kind::kGrass;
      float grass = 0.0f;
      groundOf(family, key, x, y, &kind, &grass);
      if (d < trail_w) {
        kind = trail_kind, grass = 0.0f;
        // Mud on the trail where it is wet.
        if (family != Family::kRocky && fbm2(hashOf(key, 14), x, y, 15.0, 2) > 0.45f) {
          kind = Kind::kMud;
        }
      } else {
        grass *= float(smoothstep(trail_w, trail_w + 1.5, d));  // thins out at the trail's edge
      }
      T.cells_[grid.index(i, j)] = {float(h), grass};
      T.kind_[grid.index(i, j)] = uint8_t(kind);
    }
  }

  // Carve each puddle: a smooth bowl; the water surface is flat at a level below its rim, and
  // the wet ring around it is mud.
  for (Puddle& p : T.puddles_) {
    const double r = p.radius, depth = 0.12 + 0.1 * (r / 5.0);
    const double rim = T.groundHeight(p.centre.x(), p.centre.y());
    p.level = rim - 0.45 * depth;
    const double ring = r + 1.0;
    for (int j = grid.iy(p.centre.y() - ring); j <= grid.iy(p.centre.y() + ring); ++j) {
      for (int i = grid.ix(p.centre.x() - ring); i <= grid.ix(p.centre.x() + ring); ++i) {
        const double x = grid.x0 + i * grid.res, y = grid.y0 + j * grid.res;
        const double q = std::hypot(x - p.centre.x(), y - p.centre.y()) / r;
        Cell& c = T.cells_[grid.index(i, j)];
        uint8_t& k = T.kind_[grid.index(i, j)];
        c.grass *= float(smoothstep(r + 0.2, ring, q * r));  // none on the wet ground
        if (q < 1.0) {
          const double b = 1.0 - q * q;
          c.h = float(c.h - depth * b * b);
          if (c.h < p.level) {
            c.h = float(p.level);
            k = uint8_t(Kind::kPuddle);
          } else {
            k = uint8_t(Kind::kMud);
          }
        } else if (q * r < ring && Kind(k) != Kind::kPuddle) {
          k = uint8_t(Kind::kMud);
        }
      }
    }
  }

  // Local bounds per 4 m tile, dilated by one tile: the steepest slope of h + f grass (any f)
  // and the highest surface. A marching step never leaves the dilated tile, so it is safe.
  const int tiles_x = (grid.nx + kTileCells - 1) / kTileCells;
  const int tiles_y = (grid.ny + kTileCells - 1) / kTileCells;
  std::vector<float> slope(size_t(tiles_x) * tiles_y, 0.0f), top(slope.size(), -1e30f);
  for (int j = 0; j < grid.ny; ++j) {
    for (int i = 0; i < grid.nx; ++i) {
      const Cell& a = T.cells_[grid.index(i, j)];
      const size_t t = size_t(j / kTileCells) * tiles_x + size_t(i / kTileCells);
      top[t] = std::max(top[t], a.h + a.grass);
      if (i + 1 >= grid.nx || j + 1 >= grid.ny) continue;
      const Cell& b = T.cells_[grid.index(i + 1, j)];
      const Cell& c = T.cells_[grid.index(i, j + 1)];
      const double dx = std::abs(b.h - a.h) + std::abs(b.grass - a.grass);
      const double dy = std::abs(c.h - a.h) + std::abs(c.grass - a.grass);
      slope[t] = std::max(slope[t], float(std::hypot(dx, dy) / grid.res));
    }
  }
  T.tiles_x_ = tiles_x;
  T.tiles_y_ = tiles_y;
  T.tile_slope_.assign(slope.size(), 0.0f);
  T.tile_top_.assign(slope.size(), -1e30f);
  double L = 0.0;
  for (int ty = 0; ty < tiles_y; ++ty) {
    for (int tx = 0; tx < tiles_x; ++tx) {
      const size_t t = size_t(ty) * tiles_x + tx;
      for (int oy = std::max(0, ty - 1); oy <= std::min(tiles_y - 1, ty + 1); ++oy) {
        for (int ox = std::max(0, tx - 1); ox <= std::min(tiles_x - 1, tx + 1); ++ox) {
          const size_t o = size_t(oy) * tiles_x + ox;
          T.tile_slope_[t] = std::max(T.tile_slope_[t], slope[o]);
          T.tile_top_[t] = std::max(T.tile_top_[t], top[o]);
        }
      }
      T.tile_slope_[t] = 1.05f * T.tile_slope_[t] + 0.01f;
      L = std::max(L, double(T.tile_slope_[t]));
      T.top_ = std::max(T.top_, double(T.tile_top_[t]));
    }
  }
  if (std::getenv("GEN_DEBUG")) std::fprintf(stderr, "terrain max local slope bound %.3f\n", L);
  return T;
}

double Terrain::surface(double x, double y, float f) const {
  const double u = std::clamp((x - grid_.x0) / grid_.res, 0.0, double(grid_.nx - 1) - 1e-9);
  const double v = std::clamp((y - grid_.y0) / grid_.res, 0.0, double(grid_.ny - 1) - 1e-9);
  const int i = int(u), j = int(v);
  const double a = u - i, b = v - j;
  const Cell& c00 = cells_[grid_.index(i, j)];
  const Cell& c10 = cells_[grid_.index(i + 1, j)];
  const Cell& c01 = cells_[grid_.index(i, j + 1)];
  const Cell& c11 = cells_[grid_.index(i + 1, j + 1)];
  const double h00 = c00.h + f * c00.grass, h10 = c10.h + f * c10.grass;
  const double h01 = c01.h + f * c01.grass, h11 = c11.h + f * c11.grass;
  return (h00 * (1 - a) + h10 * a) * (1 - b) + (h01 * (1 - a) + h11 * a) * b;
}

double Terrain::groundHeight(double x, double y) const { return surface(x, y, 0.0f); }

float Terrain::grassHeight(double x, double y) const {
  return float(surface(x, y, 1.0f) - surface(x, y, 0.0f));
}

Eigen::Vector3f Terrain::normal(double x, double y) const {
  const double e = grid_.res;
  const double dx = (groundHeight(x + e, y) - groundHeight(x - e, y)) / (2 * e);
  const double dy = (groundHeight(x, y + e) - groundHeight(x, y - e)) / (2 * e);
  return Eigen::Vector3f(float(-dx), float(-dy), 1.0f).normalized();
}

bool Terrain::march(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax,
                    float grass_fraction, double* t_hit) const {
  const double dh = std::hypot(d.x(), d.y());
  // The longest step that stays within the dilated tile of its start.
  const double tile = kTileCells * grid_.res;
  const double max_step = tile / std::max(dh, 1e-6);
  double f = o.z() - surface(o.x(), o.y(), grass_fraction);
  if (f <= 0.0) return false;  // the sensor is under the surface: nothing sensible to return
  double t = 0.0;
  if (o.z() > top_) {
    if (d.z() >= 0.0) return false;  // above everything and rising: sky
    t = (o.z() - top_) / -d.z();     // straight down to the highest surface's level
    if (t > tmax) return false;
  }
  Eigen::Vector3d p = o + t * d;
  if (t > 0.0) {
    if (!grid_.inside(p.x(), p.y())) return false;
    f = p.z() - surface(p.x(), p.y(), grass_fraction);
  }
  while (true) {
    if (d.z() >= 0.0 && p.z() > top_) return false;
    const size_t k = tileOf(p.x(), p.y());
    const double L = tile_slope_[k];
    // Sphere tracing with the local Lipschitz bound, or a free step while the ray stays above
    // the highest surface around.
    const double rate = L * dh - d.z();
    double step = rate > 0.0 ? f / rate : max_step;
    const double above = p.z() - tile_top_[k];
    if (above > 0.0) step = std::max(step, d.z() >= 0.0 ? max_step : above / -d.z());
    // The shortest step grows with range (0.2 m at 50 m): a crest thinner than that may be
    // stepped over, far below the point spacing there.
    step = std::clamp(step, std::max(0.03, 0.004 * t), max_step);
    const double t_next = t + step;
    if (t_next > tmax) return false;
    p = o + t_next * d;
    if (!grid_.inside(p.x(), p.y())) return false;
    const double f_next = p.z() - surface(p.x(), p.y(), grass_fraction);
    if (f_next <= 0.0) {
      double lo = t, hi = t_next;
      for (int it = 0; it < 8; ++it) {
        const double mid = 0.5 * (lo + hi);
        const Eigen::Vector3d q = o + mid * d;
        (q.z() - surface(q.x(), q.y(), grass_fraction) > 0.0 ? lo : hi) = mid;
      }
      *t_hit = hi;
      return true;
    }
    t = t_next;
    f = f_next;
  }
}

}  // namespace evidential_octomap::generator
