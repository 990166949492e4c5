// A regular 2-D grid over the scene's xy extent (row-major, cell (i, j) covers
// [x0 + i res, x0 + (i+1) res) x [y0 + j res, ...)).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace evidential_octomap::generator {

struct Grid2 {
  double x0 = 0.0, y0 = 0.0, res = 1.0;
  int nx = 0, ny = 0;

  static Grid2 covering(double xmin, double ymin, double xmax, double ymax, double res) {
    Grid2 g;
    g.res = res;
    g.x0 = std::floor(xmin / res) * res;
    g.y0 = std::floor(ymin / res) * res;
    g.nx = int(std::ceil((xmax - g.x0) / res)) + 1;
    g.ny = int(std::ceil((ymax - g.y0) / res)) + 1;
    return g;
  }
  size_t size() const { return size_t(nx) * size_t(ny); }
  size_t index(int i, int j) const { return size_t(j) * size_t(nx) + size_t(i); }
  int ix(double x) const { return std::clamp(int(std::floor((x - x0) / res)), 0, nx - 1); }
  int iy(double y) const { return std::clamp(int(std::floor((y - y0) / res)), 0, ny - 1); }
  size_t cellOf(double x, double y) const { return index(ix(x), iy(y)); }
  double cx(int i) const { return x0 + (i + 0.5) * res; }
  double cy(int j) const { return y0 + (j + 0.5) * res; }
  bool inside(double x, double y) const {
    return x >= x0 && y >= y0 && x < x0 + nx * res && y < y0 + ny * res;
  }
};

}  // namespace evidential_octomap::generator
