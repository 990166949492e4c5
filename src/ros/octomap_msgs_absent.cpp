// Built when octomap_msgs is not found (src/ros/CMakeLists.txt): the node runs without
// octomap_server's octomap_binary / octomap_full topics and services, and says so once.
#include "octomap_msgs_interface.h"

namespace evidential_octomap {

bool OctomapMsgsInterface::available() { return false; }

std::unique_ptr<OctomapMsgsInterface> OctomapMsgsInterface::create(ros::NodeHandle&,
                                                                   const NodeConfig&, WithMap) {
  ROS_INFO(
      "built without octomap_msgs: the octomap_binary / octomap_full topics and services are "
      "off (install your ROS distribution's octomap_msgs package and rebuild to get them); "
      "evidential_map and occupancy_map carry the same maps");
  return nullptr;
}

}  // namespace evidential_octomap
