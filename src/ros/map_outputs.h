// Every topic the node derives from its map. Each output has its own "older than the map" flag
// and is rebuilt only when that flag is set and the topic has a subscriber, so a subscriber that
// arrives after mapping ended (rviz ticking a display late, `rostopic echo`) gets a fresh copy at
// the next publish pass, and an output nobody listens to costs nothing.
#pragma once

#include <ros/ros.h>

#include <string>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "ros_params.h"

namespace evidential_octomap {

class MapOutputs {
 public:
  // Advertises every output on `nh` (latched unless config.latch is false).
  MapOutputs(ros::NodeHandle& nh, const NodeConfig& config);

  // The map changed: every output is older than it.
  void markStale();

  // Sends every output that is stale and has a subscriber; with `force`, every output (used
  // after reset or clear_bbx, so latched copies show the edit). Views are limited to
  // publish_radius around origin_W. Returns a one-line account for the log, "" if nothing was
  // sent.
  std::string publish(const EvidentialOcTree& tree, const ClassTable& classes,
                      const octomap::point3d& origin_W, bool force);

 private:
  struct Output {
    ros::Publisher publisher;
    bool stale = true;
    bool wanted(bool force) const { return stale && (force || publisher.getNumSubscribers() > 0); }
  };
  template <typename Message>
  void send(Output* output, Message* message, const ros::Time& stamp);

  NodeConfig config_;
  Output semantic_markers_, uncertainty_markers_, voxel_cloud_, voxel_centers_, evidential_map_,
      occupancy_map_;
};

}  // namespace evidential_octomap
