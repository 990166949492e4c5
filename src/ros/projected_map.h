// The core's 2-D maps for planners (evidential_octomap/projected_grid.h: octomap_server's
// projected_map rule) as nav_msgs/OccupancyGrid, and the per-class costs from the node's table.
// Free functions, testable without a roscore.
#pragma once

#include <nav_msgs/OccupancyGrid.h>

#include <string>
#include <utility>
#include <vector>

#include "conversions.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/projected_grid.h"

namespace evidential_octomap {

// octomap_server's projected_map.
nav_msgs::OccupancyGrid projectOccupancy(const EvidentialOcTree& tree, const HeightBand& band,
                                         const std::string& frame_id);

// The same grid with a cost per class (the core's projectClassCosts).
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
