// evidential_mapping_node: fuses per-point semantic evidence from cloud_in into an
// EvidentialOcTree and serves it (see docs/ros.md).
#include <cstdio>
#include <string>

#include <ros/ros.h>

#include "MappingServer.h"

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // log lines appear at once under roslaunch
  ros::init(argc, argv, "evidential_mapping_node");
  ros::NodeHandle nh;
  ros::NodeHandle nh_private("~");
  // As octomap_server_node: a map file as the one argument (ros::init removed the remappings).
  if (argc == 2) nh_private.setParam("map_file", std::string(argv[1]));
  try {
    evidential_octomap::MappingServer server(nh, nh_private);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("evidential_mapping_node: %s", e.what());
    return 1;
  }
  return 0;
}
