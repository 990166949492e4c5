#include "map_outputs.h"

#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <chrono>
#include <cstdio>

#include "conversions.h"
#include "visualization.h"

namespace evidential_octomap {
namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void stamp(visualization_msgs::MarkerArray* array, const ros::Time& time) {
  for (auto& m : array->markers) m.header.stamp = time;
}
template <typename Message>
void stamp(Message* message, const ros::Time& time) {
  message->header.stamp = time;
}

}  // namespace

MapOutputs::MapOutputs(ros::NodeHandle& nh, const NodeConfig& config) : config_(config) {
  const bool latch = config_.latch;
  semantic_markers_.publisher =
      nh.advertise<visualization_msgs::MarkerArray>("occupied_cells_vis_array", 1, latch);
  uncertainty_markers_.publisher =
      nh.advertise<visualization_msgs::MarkerArray>("uncertainty_cells_vis_array", 1, latch);
  voxel_cloud_.publisher = nh.advertise<sensor_msgs::PointCloud2>("semantic_cloud", 1, latch);
  // octomap_server's name for the same cloud.
  voxel_centers_.publisher =
      nh.advertise<sensor_msgs::PointCloud2>("octomap_point_cloud_centers", 1, latch);
  evidential_map_.publisher = nh.advertise<EvidentialMap>("evidential_map", 1, latch);
  occupancy_map_.publisher = nh.advertise<OccupancyMap>("occupancy_map", 1, latch);
}

void MapOutputs::markStale() {
  for (Output* o : {&semantic_markers_, &uncertainty_markers_, &voxel_cloud_, &voxel_centers_,
                    &evidential_map_, &occupancy_map_})
    o->stale = true;
}

template <typename Message>
void MapOutputs::send(Output* output, Message* message, const ros::Time& time) {
  stamp(message, time);
  output->publisher.publish(*message);
  output->stale = false;
}

std::string MapOutputs::publish(const EvidentialOcTree& tree, const ClassTable& classes,
                                const octomap::point3d& origin_W, bool force) {
  const auto t0 = std::chrono::steady_clock::now();
  const ros::Time now = ros::Time::now();
  std::string sent;
  char part[96];

  const bool views = semantic_markers_.wanted(force) || uncertainty_markers_.wanted(force) ||
                     voxel_cloud_.wanted(force) || voxel_centers_.wanted(force);
  if (views) {
    Box box;
    if (config_.publish_radius > 0.0) {
      const octomap::point3d r(config_.publish_radius, config_.publish_radius,
                               config_.publish_radius);
      box.min = origin_W - r;
      box.max = origin_W + r;
    }
    const std::vector<VoxelView> voxels = occupiedVoxels(tree, box);
    const unsigned depth = tree.getTreeDepth();
    if (semantic_markers_.wanted(force)) {
      auto markers = semanticMarkers(voxels, classes, config_.frame_id, depth);
      send(&semantic_markers_, &markers, now);
    }
    if (uncertainty_markers_.wanted(force)) {
      auto markers = uncertaintyMarkers(voxels, config_.uncertainty_range, config_.frame_id, depth);
      send(&uncertainty_markers_, &markers, now);
    }
    if (voxel_cloud_.wanted(force) || voxel_centers_.wanted(force)) {
      sensor_msgs::PointCloud2 cloud = toPointCloud2(voxels, classes, config_.frame_id);
      if (voxel_cloud_.wanted(force)) send(&voxel_cloud_, &cloud, now);
      if (voxel_centers_.wanted(force)) send(&voxel_centers_, &cloud, now);
    }
    std::snprintf(part, sizeof(part), " views of %zu voxels (%.0f ms)", voxels.size(), msSince(t0));
    sent += part;
  }
  if (evidential_map_.wanted(force)) {
    const auto t = std::chrono::steady_clock::now();
    EvidentialMap msg = toEvidentialMap(tree, config_.frame_id);
    send(&evidential_map_, &msg, now);
    std::snprintf(part, sizeof(part), " evidential_map (%.1f MB, %.0f ms)", msg.data.size() / 1e6,
                  msSince(t));
    sent += part;
  }
  if (occupancy_map_.wanted(force)) {
    const auto t = std::chrono::steady_clock::now();
    OccupancyMap msg = toOccupancyMap(tree, config_.frame_id);
    send(&occupancy_map_, &msg, now);
    std::snprintf(part, sizeof(part), " occupancy_map (%.0f ms)", msSince(t));
    sent += part;
  }
  return sent;
}

}  // namespace evidential_octomap
