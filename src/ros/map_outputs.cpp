#include "map_outputs.h"

#include <cv_bridge/cv_bridge.h>
#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <chrono>
#include <cstdio>

#include "conversions.h"
#include "legend.h"
#include "projected_map.h"
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

template <typename Message>
void stampAndSend(StaleOutput* output, Message message, const ros::Time& time) {
  stamp(&message, time);
  output->send(message);
}

std::string uncertaintyName(const EvidentialOcTree& tree, UncertaintyView view) {
  if (view == UncertaintyView::kErrorProbability) return "error probability";  // P(label wrong)
  return tree.rule().uncertaintyIsMass() ? "vacuity u" : "uncertainty (Dirichlet var.)";
}

}  // namespace

MapOutputs::MapOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, const NodeConfig& config,
                       const ClassTable& classes, OctomapMsgsInterface::WithMap with_map)
    : config_(config) {
  const bool latch = config_.latch;
  using visualization_msgs::MarkerArray;
  semantic_markers_.publisher = nh.advertise<MarkerArray>("occupied_cells_vis_array", 1, latch);
  uncertainty_markers_.publisher =
      nh.advertise<MarkerArray>("uncertainty_cells_vis_array", 1, latch);
  conflict_markers_.publisher = nh.advertise<MarkerArray>("conflict_cells_vis_array", 1, latch);
  free_markers_.publisher = nh.advertise<MarkerArray>("free_cells_vis_array", 1, latch);
  voxel_cloud_.publisher = nh.advertise<sensor_msgs::PointCloud2>("semantic_cloud", 1, latch);
  // octomap_server's name for the same cloud.
  voxel_centers_.publisher =
      nh.advertise<sensor_msgs::PointCloud2>("octomap_point_cloud_centers", 1, latch);
  evidential_map_.publisher = nh.advertise<EvidentialMap>("evidential_map", 1, latch);
  occupancy_map_.publisher = nh.advertise<OccupancyMap>("occupancy_map", 1, latch);
  projected_map_.publisher = nh.advertise<nav_msgs::OccupancyGrid>("projected_map", 1, latch);
  if (!config_.class_costs.empty()) {
    class_costs_ = classCosts(classes, config_.class_costs, config_.class_cost_default);
    projected_cost_map_.publisher =
        nh.advertise<nav_msgs::OccupancyGrid>("projected_cost_map", 1, latch);
  }
  legend_ = pnh.advertise<sensor_msgs::Image>("legend", 1, true);
  octomap_msgs_ = OctomapMsgsInterface::create(nh, config_, std::move(with_map));
}

MapOutputs::~MapOutputs() = default;

void MapOutputs::markStale() {
  for (StaleOutput* o : {&semantic_markers_, &uncertainty_markers_, &conflict_markers_,
                         &free_markers_, &voxel_cloud_, &voxel_centers_, &evidential_map_,
                         &occupancy_map_, &projected_map_, &projected_cost_map_})
    o->stale = true;
  if (octomap_msgs_) octomap_msgs_->markStale();
}

std::string MapOutputs::publish(const EvidentialOcTree& tree, const ClassTable& classes,
                                const octomap::point3d& origin_W, bool force) {
  // Until the uncertainty view is built, the legend shows the configured range, not yet fitted.
  if (!legend_sent_)
    publishLegend(classes, resolveRange({}, config_.uncertainty_range, config_.uncertainty_view),
                  uncertaintyName(tree, config_.uncertainty_view));
  std::string sent = publishViews(tree, classes, origin_W, force);
  if (!wholeMapsDue(force)) return sent;  // still stale: sent once the period has passed
  const auto t0 = std::chrono::steady_clock::now();
  std::string maps = publishMaps(tree, classes, force);
  if (octomap_msgs_) maps += octomap_msgs_->publish(tree, classes, force);
  if (!maps.empty()) {
    last_maps_sent_ = ros::WallTime::now();
    last_maps_ms_ = msSince(t0);
  }
  return sent + maps;
}

bool MapOutputs::wholeMapsDue(bool force) const {
  if (force || config_.full_map_period <= 0.0 || last_maps_sent_.isZero()) return true;
  return (ros::WallTime::now() - last_maps_sent_).toSec() >= config_.full_map_period;
}

std::string MapOutputs::publishViews(const EvidentialOcTree& tree, const ClassTable& classes,
                                     const octomap::point3d& origin_W, bool force) {
  const bool occupied = semantic_markers_.wanted(force) || uncertainty_markers_.wanted(force) ||
                        conflict_markers_.wanted(force) || voxel_cloud_.wanted(force) ||
                        voxel_centers_.wanted(force);
  const bool free = free_markers_.wanted(force);
  if (!occupied && !free) return "";
  const auto t0 = std::chrono::steady_clock::now();
  const ros::Time now = ros::Time::now();
  Box box;
  if (config_.publish_radius > 0.0) {
    const octomap::point3d r(config_.publish_radius, config_.publish_radius,
                             config_.publish_radius);
    box.min = origin_W - r;
    box.max = origin_W + r;
  }
  const unsigned depth = tree.getTreeDepth();
  const std::string& frame = config_.frame_id;
  size_t n_occupied = 0, n_free = 0;
  if (occupied) {
    const std::vector<VoxelView> voxels = occupiedVoxels(tree, box, config_.occupancy_band);
    n_occupied = voxels.size();
    if (semantic_markers_.wanted(force))
      stampAndSend(&semantic_markers_, semanticMarkers(voxels, classes, frame, depth), now);
    if (uncertainty_markers_.wanted(force)) {
      const UncertaintyView view = config_.uncertainty_view;
      const UncertaintyRange range = resolveRange(voxels, config_.uncertainty_range, view);
      stampAndSend(&uncertainty_markers_, uncertaintyMarkers(voxels, range, view, frame, depth),
                   now);
      publishLegend(classes, range, uncertaintyName(tree, view));
    }
    if (conflict_markers_.wanted(force))
      stampAndSend(&conflict_markers_, conflictMarkers(voxels, frame, depth), now);
    if (voxel_cloud_.wanted(force) || voxel_centers_.wanted(force)) {
      const sensor_msgs::PointCloud2 cloud = toPointCloud2(voxels, classes, frame);
      if (voxel_cloud_.wanted(force)) stampAndSend(&voxel_cloud_, cloud, now);
      if (voxel_centers_.wanted(force)) stampAndSend(&voxel_centers_, cloud, now);
    }
  }
  if (free) {
    const std::vector<VoxelView> voxels = freeVoxels(tree, box, config_.occupancy_band);
    n_free = voxels.size();
    stampAndSend(&free_markers_, freeMarkers(voxels, frame, depth), now);
  }
  last_views_ms_ = msSince(t0);
  char part[96];
  std::snprintf(part, sizeof(part), " views of %zu occupied + %zu free voxels (%.0f ms)",
                n_occupied, n_free, last_views_ms_);
  return part;
}

std::string MapOutputs::publishMaps(const EvidentialOcTree& tree, const ClassTable&, bool force) {
  const ros::Time now = ros::Time::now();
  const std::string& frame = config_.frame_id;
  std::string sent;
  char part[96];
  if (evidential_map_.wanted(force)) {
    const auto t = std::chrono::steady_clock::now();
    EvidentialMap msg = toEvidentialMap(tree, frame);
    const double mb = msg.data.size() / 1e6;
    stampAndSend(&evidential_map_, std::move(msg), now);
    std::snprintf(part, sizeof(part), " evidential_map (%.1f MB, %.0f ms)", mb, msSince(t));
    sent += part;
  }
  auto timed = [&](const char* name, auto build_and_send) {
    const auto t = std::chrono::steady_clock::now();
    build_and_send();
    std::snprintf(part, sizeof(part), " %s (%.0f ms)", name, msSince(t));
    sent += part;
  };
  if (occupancy_map_.wanted(force))
    timed("occupancy_map",
          [&] { stampAndSend(&occupancy_map_, toOccupancyMap(tree, frame), now); });
  if (projected_map_.wanted(force))
    timed("projected_map", [&] {
      stampAndSend(&projected_map_, projectOccupancy(tree, config_.occupancy_band, frame), now);
    });
  if (!class_costs_.empty() && projected_cost_map_.wanted(force))
    timed("projected_cost_map", [&] {
      stampAndSend(&projected_cost_map_,
                   projectClassCosts(tree, config_.occupancy_band, class_costs_,
                                     static_cast<int8_t>(config_.class_cost_default), frame),
                   now);
    });
  return sent;
}

// The legend changes only with the uncertainty range (automatic ranges follow the map) or the
// rule; it is sent when either differs from what was last sent.
void MapOutputs::publishLegend(const ClassTable& classes, const UncertaintyRange& range,
                               const std::string& uncertainty_name) {
  if (legend_sent_ && range.min == legend_range_.min && range.max == legend_range_.max &&
      uncertainty_name == legend_name_)
    return;
  cv_bridge::CvImage image;
  image.header.stamp = ros::Time::now();
  image.encoding = "rgb8";
  image.image = renderLegend(classes, range, uncertainty_name);
  legend_.publish(image.toImageMsg());
  legend_range_ = range;
  legend_name_ = uncertainty_name;
  legend_sent_ = true;
}

}  // namespace evidential_octomap
