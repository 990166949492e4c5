#include "map_outputs.h"

#include <cv_bridge/cv_bridge.h>
#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <chrono>
#include <cstdio>
#include <memory>

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
  output->publisher.publish(message);
}

// Stamps a message built under the map lock and leaves its send in the outbox.
template <typename Message>
void sendLater(StaleOutput* output, Message message, const ros::Time& time, Outbox* outbox) {
  stamp(&message, time);
  auto shared = std::make_shared<Message>(std::move(message));
  output->claim();
  outbox->push_back([output, shared] { output->publisher.publish(*shared); });
}

std::string uncertaintyName(const EvidentialOcTree& tree, UncertaintyView view) {
  if (view == UncertaintyView::kErrorProbability) return "error probability";  // P(label wrong)
  return tree.rule().uncertaintyIsMass() ? "vacuity u" : "uncertainty (Dirichlet var.)";
}

}  // namespace

MapOutputs::MapOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, const NodeConfig& config,
                       const ClassTable& classes, OctomapMsgsInterface::WithMap with_map)
    : config_(config), with_map_(with_map) {
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

template <typename Visit>
void MapOutputs::hold(Visit visit) {
  with_map_([&](const EvidentialOcTree& tree, const ClassTable&) {
    const auto t0 = std::chrono::steady_clock::now();
    visit(tree);
    longest_hold_ms_ = std::max(longest_hold_ms_, msSince(t0));
  });
}

std::string MapOutputs::publish(const ClassTable& classes, const octomap::point3d& origin_W,
                                bool force) {
  longest_hold_ms_ = 0.0;
  ViewPlan plan;
  hold([&](const EvidentialOcTree& tree) { plan = planViews(tree, origin_W, force); });
  // Until the uncertainty view is built, the legend shows the configured range, not yet fitted.
  if (!legend_sent_)
    publishLegend(classes, resolveRange({}, config_.uncertainty_range, config_.uncertainty_view),
                  plan.uncertainty_name);
  std::string sent = readAndSendViews(plan, classes);
  if (!wholeMapsDue(force)) return sent;  // still stale: sent once the period has passed
  const auto t0 = std::chrono::steady_clock::now();
  Outbox outbox;
  std::string maps;
  hold([&](const EvidentialOcTree& tree) {
    maps = publishMaps(tree, force, &outbox);
    if (octomap_msgs_) maps += octomap_msgs_->publish(tree, classes, force, &outbox);
  });
  for (const auto& send : outbox) send();  // serialised and sent outside the map lock
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

// Map lock held: which views are due (claimed now, so an insert from here on marks them stale
// again) and the chunks to read them from.
MapOutputs::ViewPlan MapOutputs::planViews(const EvidentialOcTree& tree,
                                           const octomap::point3d& origin_W, bool force) {
  ViewPlan plan;
  plan.uncertainty_name = uncertaintyName(tree, config_.uncertainty_view);
  for (StaleOutput* o : {&semantic_markers_, &uncertainty_markers_, &conflict_markers_,
                         &voxel_cloud_, &voxel_centers_, &free_markers_}) {
    if (!o->wanted(force)) continue;
    o->claim();
    plan.due.push_back(o);
    (o == &free_markers_ ? plan.free : plan.occupied) = true;
  }
  if (plan.due.empty()) return plan;
  Box box;
  if (config_.publish_radius > 0.0) {
    const octomap::point3d r(config_.publish_radius, config_.publish_radius,
                             config_.publish_radius);
    box.min = origin_W - r;
    box.max = origin_W + r;
  }
  plan.chunks = viewChunks(tree, box);
  plan.depth = tree.getTreeDepth();
  plan.stamp = ros::Time::now();
  return plan;
}

std::string MapOutputs::readAndSendViews(const ViewPlan& plan, const ClassTable& classes) {
  if (plan.due.empty()) return "";
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<VoxelView> occupied, free;
  for (const ViewChunk& chunk : plan.chunks)  // one short hold per chunk
    hold([&](const EvidentialOcTree& tree) {
      readChunk(tree, chunk, config_.occupancy_band, plan.occupied ? &occupied : nullptr,
                plan.free ? &free : nullptr);
    });
  const std::string& frame = config_.frame_id;
  if (plan.isDue(&semantic_markers_))
    stampAndSend(&semantic_markers_, semanticMarkers(occupied, classes, frame, plan.depth),
                 plan.stamp);
  if (plan.isDue(&uncertainty_markers_)) {
    const UncertaintyView view = config_.uncertainty_view;
    const UncertaintyRange range = resolveRange(occupied, config_.uncertainty_range, view);
    stampAndSend(&uncertainty_markers_, uncertaintyMarkers(occupied, range, view, frame, plan.depth),
                 plan.stamp);
    publishLegend(classes, range, plan.uncertainty_name);
  }
  if (plan.isDue(&conflict_markers_))
    stampAndSend(&conflict_markers_, conflictMarkers(occupied, frame, plan.depth), plan.stamp);
  if (plan.isDue(&voxel_cloud_) || plan.isDue(&voxel_centers_)) {
    const sensor_msgs::PointCloud2 cloud = toPointCloud2(occupied, classes, frame);
    if (plan.isDue(&voxel_cloud_)) stampAndSend(&voxel_cloud_, cloud, plan.stamp);
    if (plan.isDue(&voxel_centers_)) stampAndSend(&voxel_centers_, cloud, plan.stamp);
  }
  if (plan.free) stampAndSend(&free_markers_, freeMarkers(free, frame, plan.depth), plan.stamp);
  last_views_ms_ = msSince(t0);
  char part[128];
  std::snprintf(part, sizeof(part), " views of %zu occupied + %zu free voxels (%.0f ms, %zu chunks)",
                occupied.size(), free.size(), last_views_ms_, plan.chunks.size());
  return part;
}

std::string MapOutputs::publishMaps(const EvidentialOcTree& tree, bool force, Outbox* outbox) {
  const ros::Time now = ros::Time::now();
  const std::string& frame = config_.frame_id;
  std::string sent;
  char part[96];
  if (evidential_map_.wanted(force)) {
    const auto t = std::chrono::steady_clock::now();
    EvidentialMap msg = toEvidentialMap(tree, frame);
    const double mb = msg.data.size() / 1e6;
    sendLater(&evidential_map_, std::move(msg), now, outbox);
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
          [&] { sendLater(&occupancy_map_, toOccupancyMap(tree, frame), now, outbox); });
  if (projected_map_.wanted(force))
    timed("projected_map", [&] {
      sendLater(&projected_map_, projectOccupancy(tree, config_.occupancy_band, frame), now,
                outbox);
    });
  if (!class_costs_.empty() && projected_cost_map_.wanted(force))
    timed("projected_cost_map", [&] {
      sendLater(&projected_cost_map_,
                projectClassCosts(tree, config_.occupancy_band, class_costs_,
                                  static_cast<int8_t>(config_.class_cost_default), frame),
                now, outbox);
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
