#include "plain_octomap.h"

#include "bench_data.h"

#ifdef _OPENMP
#error "plain_octomap.cpp must be compiled without OpenMP (see bench/CMakeLists.txt)"
#endif

namespace evbench {

__attribute__((noinline)) double plainInsert(octomap::OcTree& tree,
                                             const octomap::Pointcloud& points_W,
                                             const octomap::point3d& origin_W, double max_range,
                                             bool discretize) {
  const auto start = Clock::now();
  tree.insertPointCloud(points_W, origin_W, max_range, /*lazy_eval=*/false, discretize);
  return msSince(start);
}

}  // namespace evbench
