// 2-D maps for planners, projected from the 3-D map as octomap_server's projected_map:
// every leaf whose centre lies in [min_z, max_z] marks the cells under it occupied (100) or free
// (0, unless another leaf of the column is occupied); cells no such leaf covers are unknown (-1).
// The grid covers the tree's metric x-y extent at leaf resolution. Free functions, testable
// without a roscore.
#pragma once

#include <nav_msgs/OccupancyGrid.h>

#include <string>
#include <utility>
#include <vector>

#include "conversions.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// octomap_server's projected_map.
nav_msgs::OccupancyGrid projectOccupancy(const EvidentialOcTree& tree, const HeightBand& band,
                                         const std::string& frame_id);

// The same grid with a cost per class: an occupied leaf marks its cells with the cost of its
// class (`class_costs`, one value 0..100 per class; `no_class_cost` for occupied leaves without
// evidence), the largest cost of the column wins; free and unknown as in projectOccupancy. With
// ground classes at cost 0, a planner sees the road as drivable where projected_map sees an
// obstacle.
nav_msgs::OccupancyGrid projectClassCosts(const EvidentialOcTree& tree, const HeightBand& band,
                                          const std::vector<int8_t>& class_costs,
                                          int8_t no_class_cost, const std::string& frame_id);

// Per-class costs from a name -> cost table (names of `classes`); classes the table leaves out
// cost `default_cost`. Throws std::invalid_argument for an unknown class name or a cost outside
// 0..100.
std::vector<int8_t> classCosts(const ClassTable& classes,
                               const std::vector<std::pair<std::string, int>>& table,
                               int default_cost);

}  // namespace evidential_octomap
