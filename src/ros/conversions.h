// ROS <-> core conversions (free functions, no node state, testable without a roscore):
//   PointCloud2 with per-point evidence  ->  octomap::Pointcloud + N x C evidence,
//   EvidentialOcTree                     ->  voxel list  ->  PointCloud2 (label, uncertainty, rgb).
#pragma once

#include <octomap/Pointcloud.h>
#include <octomap/math/Pose6D.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "evidential_octomap/EvidentialMap.h"
#include "evidential_octomap/OccupancyMap.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/pointcloud2_reader.h"
#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap {

// The core's readPointCloud2 (pointcloud2_reader.h) of the message.
std::string fromPointCloud2(const sensor_msgs::PointCloud2& msg, const CloudReadOptions& options,
                            SemanticCloud* out);

// One leaf as drawn and published.
struct VoxelView {
  octomap::point3d center;
  double size = 0.0;   // edge length [m]
  unsigned depth = 0;  // tree depth of the leaf
  int label = -1;      // argmax class, -1: no semantic evidence
  float uncertainty = 1.0f;        // VoxelOpinion::uncertainty (dempster: vacuity u)
  float error_probability = 1.0f;  // FusionRule::errorProbability: P(label wrong)
  float conflict = 0.0f;           // VoxelOpinion::conflict
};

// Axis-aligned box in the map frame; empty (min > max) means "everything".
struct Box {
  octomap::point3d min{1.f, 1.f, 1.f};
  octomap::point3d max{0.f, 0.f, 0.f};
  bool empty() const { return min.x() > max.x(); }
};

// A z interval [m] (octomap_server's pointcloud_min_z/max_z, occupancy_min_z/max_z); unbounded
// by default.
struct HeightBand {
  double min_z = -std::numeric_limits<double>::infinity();
  double max_z = std::numeric_limits<double>::infinity();
  bool contains(double z) const { return z >= min_z && z <= max_z; }
  bool unbounded() const { return std::isinf(min_z) && std::isinf(max_z); }
};

// The view of one leaf; an occupied leaf with semantics carries its opinion, a free one none.
VoxelView viewOfLeaf(const EvidentialOcTree& tree, const EvidentialOcTreeNode& node,
                     const octomap::point3d& center, double size, unsigned depth);

// Keeps the points of `scan` whose height in frame F lies in `band`, with their evidence rows;
// T_F_S maps the cloud's frame into F. Returns how many points were removed.
size_t keepHeightBand(const octomap::pose6d& T_F_S, const HeightBand& band, int num_classes,
                      SemanticCloud* scan);

// Voxel centres as PointCloud2: x, y, z (float32), label (int32), uncertainty (float32),
// rgb (float32-packed class colour, grey when unlabelled), conflict, error_probability (float32).
sensor_msgs::PointCloud2 toPointCloud2(const std::vector<VoxelView>& voxels,
                                       const ClassTable& classes, const std::string& frame_id);

// The whole tree as our EvidentialMap message (.ot bytes, C, class names, rule); stamp unset.
EvidentialMap toEvidentialMap(const EvidentialOcTree& tree, const std::string& frame_id);
// Occupancy only, as .bt bytes any OctoMap tool reads; stamp unset.
OccupancyMap toOccupancyMap(const EvidentialOcTree& tree, const std::string& frame_id);

// Packs a colour as PCL/rviz expect in a float32 `rgb` field.
float packRgb(const ClassTable::Rgb& rgb);

}  // namespace evidential_octomap
