// Plain OctoMap reference, compiled in its own translation unit without OpenMP so that every
// OcTree call runs exactly the code of the distribution's liboctomap (Debian's is built without
// OpenMP, i.e. single-threaded), whatever flags the rest of the bench uses.
#pragma once

#include <octomap/OcTree.h>

namespace evbench {

// insertPointCloud(scan, origin, max_range, lazy_eval = false, discretize); returns wall ms.
double plainInsert(octomap::OcTree& tree, const octomap::Pointcloud& points_W,
                   const octomap::point3d& origin_W, double max_range, bool discretize);

}  // namespace evbench
