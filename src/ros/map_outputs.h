// Every topic the node derives from its map. Each output has its own "older than the map" flag
// (StaleOutput) and is rebuilt only when that flag is set and the topic has a subscriber, so a
// subscriber that arrives after mapping ended (rviz ticking a display late, `rostopic echo`) gets
// a fresh copy at the next publish pass, and an output nobody listens to costs nothing.
#pragma once

#include <ros/ros.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "octomap_msgs_interface.h"
#include "ros_params.h"
#include "stale_output.h"
#include "view_chunks.h"

namespace evidential_octomap {

class MapOutputs {
 public:
  // Advertises every output on `nh` (latched unless config.latch is false) and the legend on
  // `pnh`; `with_map` runs a function on the map under the node's lock (octomap_msgs services).
  MapOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, const NodeConfig& config,
             const ClassTable& classes, OctomapMsgsInterface::WithMap with_map);
  ~MapOutputs();

  // The map changed: every output is older than it.
  void markStale();

  // Sends every output that is stale and has a subscriber; with `force`, every output (used
  // after reset or clear_bbx, so latched copies show the edit). Reads the map through
  // `with_map` in short holds of the map lock (so the caller must not hold it): the views
  // chunk by chunk (view_chunks.h), the whole-map outputs in one hold; markers are built and
  // messages serialised and sent outside it. Views are limited to publish_radius around
  // origin_W and to occupancy_min_z..max_z. Returns a one-line account for the log, "" if
  // nothing was sent. Not reentrant: one pass at a time.
  std::string publish(const ClassTable& classes, const octomap::point3d& origin_W, bool force);

  // The longest single hold of the map lock in the last pass [ms]: what an insert waited at most.
  double longestHoldMs() const { return longest_hold_ms_; }
  // Wall time [ms] of the last views and the last whole-map outputs that were sent (~status).
  double lastViewsMs() const { return last_views_ms_; }
  double lastMapsMs() const { return last_maps_ms_; }

 private:
  // The views due in one pass, and where to read them from.
  struct ViewPlan {
    std::vector<StaleOutput*> due;  // claimed
    bool occupied = false, free = false;
    std::vector<ViewChunk> chunks;
    unsigned depth = 0;
    std::string uncertainty_name;
    ros::Time stamp;
    bool isDue(const StaleOutput* o) const {
      return std::find(due.begin(), due.end(), o) != due.end();
    }
  };
  template <typename Visit>
  void hold(Visit visit);  // runs visit(tree) under the map lock, timed
  ViewPlan planViews(const EvidentialOcTree& tree, const octomap::point3d& origin_W, bool force);
  std::string readAndSendViews(const ViewPlan& plan, const ClassTable& classes);
  std::string publishMaps(const EvidentialOcTree& tree, bool force, Outbox* outbox);
  // The whole-map outputs may be rebuilt now (full_map_period has passed, or `force`).
  bool wholeMapsDue(bool force) const;
  void publishLegend(const ClassTable& classes, const UncertaintyRange& range,
                     const std::string& uncertainty_name);

  NodeConfig config_;
  OctomapMsgsInterface::WithMap with_map_;
  double longest_hold_ms_ = 0.0;
  std::vector<int8_t> class_costs_;  // per class; empty: no projected_cost_map
  StaleOutput semantic_markers_, uncertainty_markers_, conflict_markers_, free_markers_,
      voxel_cloud_, voxel_centers_, evidential_map_, occupancy_map_, projected_map_,
      projected_cost_map_;
  ros::Publisher legend_;  // latched image; sent when its range or rule name changes
  bool legend_sent_ = false;
  UncertaintyRange legend_range_;
  std::string legend_name_;
  std::unique_ptr<OctomapMsgsInterface> octomap_msgs_;  // nullptr: built without octomap_msgs
  ros::WallTime last_maps_sent_;  // zero: never
  double last_views_ms_ = 0.0, last_maps_ms_ = 0.0;
};

}  // namespace evidential_octomap
