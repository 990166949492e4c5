// octomap_server's interface over octomap_msgs (optional at build time, as Debian ships no
// octomap_msgs): the topics `octomap_binary` (occupancy, OcTree) and `octomap_full` (the
// semantic map as a ColorOcTree), `evidential_octomap_full` (the EvidentialOcTree itself), and
// the GetOctomap services `octomap_binary` and `octomap_full`. Built without octomap_msgs,
// create() says once that these are off and returns nullptr.
#pragma once

#include <ros/ros.h>

#include <functional>
#include <memory>
#include <string>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "ros_params.h"
#include "stale_output.h"

namespace evidential_octomap {

class OctomapMsgsInterface {
 public:
  // Runs a function on the map under the node's map lock (for the services).
  using MapVisitor = std::function<void(const EvidentialOcTree&, const ClassTable&)>;
  using WithMap = std::function<void(const MapVisitor&)>;

  // Whether this build has octomap_msgs.
  static bool available();
  // Advertises the topics (latched unless config.latch is false) and services; nullptr (and one
  // log line saying why) when built without octomap_msgs.
  static std::unique_ptr<OctomapMsgsInterface> create(ros::NodeHandle& nh, const NodeConfig& config,
                                                      WithMap with_map);
  virtual ~OctomapMsgsInterface() = default;

  // As MapOutputs: mark every topic older than the map; build the stale ones with subscribers
  // (all with `force`; map lock held), leave their sends in `outbox`, and return an account for
  // the log.
  virtual void markStale() = 0;
  virtual std::string publish(const EvidentialOcTree& tree, const ClassTable& classes, bool force,
                              Outbox* outbox) = 0;
};

}  // namespace evidential_octomap
