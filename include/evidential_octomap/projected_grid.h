// 2-D grids for planners, projected from the 3-D map as octomap_server's projected_map: every
// leaf whose centre height lies in [min_z, max_z] marks the cells under it, an occupied leaf with
// its cost (100, or its class's), a free one with 0, and a cell keeps the largest mark of its
// column; a cell no such leaf covers is unknown (-1). The grid spans the x-y extent of all the
// map's leaves at leaf resolution. The ROS 1 node's projected maps and the Python package's.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

struct ProjectedGrid {
  unsigned width = 0, height = 0;         // cells along x and along y
  double origin_x = 0.0, origin_y = 0.0;  // the outer corner of cell (0, 0) [m]
  double resolution = 0.0;                // cell edge [m]
  std::vector<int8_t> cells;  // row-major, row j at y: 100 occupied, 0 free, -1 unknown
};

// octomap_server's projected_map.
ProjectedGrid projectOccupancy(const EvidentialOcTree& tree,
                               double min_z = -std::numeric_limits<double>::infinity(),
                               double max_z = std::numeric_limits<double>::infinity());

// The same with a cost per class: an occupied leaf marks its cells with the cost of its class
// (`class_costs`, one value 0..100 per class; `no_class_cost` for occupied leaves without
// evidence). With ground classes at cost 0, a planner sees the road as drivable where
// projected_map sees an obstacle.
ProjectedGrid projectClassCosts(const EvidentialOcTree& tree, double min_z, double max_z,
                                const std::vector<int8_t>& class_costs, int8_t no_class_cost);

}  // namespace evidential_octomap
