// rviz views of the map, kept apart from mapping: semantic markers (class colours from the class
// table), uncertainty and conflict markers (evidential_octomap::uncertaintyColor ramp) and free
// space. One CUBE_LIST marker per tree depth, as octomap_server does; depths without voxels get
// a DELETE so stale cubes vanish.
#pragma once

#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <vector>

#include "conversions.h"
#include "evidential_octomap/class_table.h"

namespace evidential_octomap {

// What the uncertainty view colours (~uncertainty_view): the map's probability that a voxel's
// label is wrong (1 - max_c p_c, the default: it detects wrong labels best,
// docs/experiments/results.md), or the vacuity u (how little evidence the voxel holds; sbki/ebs:
// the Dirichlet variance).
enum class UncertaintyView { kErrorProbability, kVacuity };
// "error_probability" or "vacuity"; throws std::invalid_argument naming both otherwise.
UncertaintyView uncertaintyViewFromName(const std::string& name);
float shownUncertainty(const VoxelView& voxel, UncertaintyView view);

// Colour range of the uncertainty view: fixed [min, max], or automatic: fitted to the shown
// voxels' values, their 5th to 95th percentile.
struct UncertaintyRange {
  bool automatic = false;
  double min = 0.0;
  double max = 1.0;
};

visualization_msgs::MarkerArray semanticMarkers(const std::vector<VoxelView>& voxels,
                                                const ClassTable& classes,
                                                const std::string& frame_id, unsigned tree_depth);

// The range actually drawn: `range` itself, or the voxels' 5th..95th percentile of the shown
// value when automatic (then `automatic` stays true, for the legend).
UncertaintyRange resolveRange(const std::vector<VoxelView>& voxels, const UncertaintyRange& range,
                              UncertaintyView view);

visualization_msgs::MarkerArray uncertaintyMarkers(const std::vector<VoxelView>& voxels,
                                                   const UncertaintyRange& range,
                                                   UncertaintyView view,
                                                   const std::string& frame_id,
                                                   unsigned tree_depth);

// Conflict in [0, 1) (VoxelOpinion::conflict) on the same colour ramp, fixed range 0..1.
visualization_msgs::MarkerArray conflictMarkers(const std::vector<VoxelView>& voxels,
                                                const std::string& frame_id, unsigned tree_depth);

// Free leaves in octomap_server's translucent green.
visualization_msgs::MarkerArray freeMarkers(const std::vector<VoxelView>& voxels,
                                            const std::string& frame_id, unsigned tree_depth);

}  // namespace evidential_octomap
