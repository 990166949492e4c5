// rviz views of the map, kept apart from mapping: semantic markers (class colours from the class
// table) and uncertainty markers (evidential_octomap::uncertaintyColor). One CUBE_LIST marker per
// tree depth, as octomap_server does; depths without voxels get a DELETE so stale cubes vanish.
#pragma once

#include <string>
#include <vector>

#include <visualization_msgs/MarkerArray.h>

#include "conversions.h"
#include "evidential_octomap/class_table.h"

namespace evidential_octomap {

// Colour range of the uncertainty view: fixed [min, max] or the shown voxels' own range.
struct UncertaintyRange {
  bool automatic = false;
  double min = 0.0;
  double max = 1.0;
};

visualization_msgs::MarkerArray semanticMarkers(const std::vector<VoxelView>& voxels,
                                                const ClassTable& classes,
                                                const std::string& frame_id, unsigned tree_depth);

visualization_msgs::MarkerArray uncertaintyMarkers(const std::vector<VoxelView>& voxels,
                                                   const UncertaintyRange& range,
                                                   const std::string& frame_id, unsigned tree_depth);

}  // namespace evidential_octomap
