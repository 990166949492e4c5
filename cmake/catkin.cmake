# ROS 1 part, stage 1 (included by the top-level CMakeLists.txt before the core library):
# find catkin and the ROS packages the node uses, generate messages/services, declare the package.
# Stage 2 (node, tests, install rules) is src/ros/CMakeLists.txt, added after the core library.

set(EVIDENTIAL_OCTOMAP_CATKIN_COMPONENTS
  roscpp roslib std_msgs std_srvs sensor_msgs geometry_msgs visualization_msgs diagnostic_msgs
  tf2 tf2_ros message_filters cv_bridge dynamic_reconfigure nodelet pluginlib)

find_package(catkin REQUIRED COMPONENTS message_generation ${EVIDENTIAL_OCTOMAP_CATKIN_COMPONENTS})

add_message_files(DIRECTORY msg FILES
  EvidentialMap.msg
  MappingStatus.msg
  OccupancyMap.msg)
add_service_files(DIRECTORY srv FILES
  ClearBbx.srv
  LoadMap.srv
  QueryMap.srv
  SaveMap.srv)
generate_messages(DEPENDENCIES std_msgs geometry_msgs)

# Run-time parameters (DESIGN §5): dynamic_reconfigure's C++ server and cfg generator are in
# Debian's libdynamic-reconfigure-config-init-mutex-dev / python3-dynamic-reconfigure.
generate_dynamic_reconfigure_options(src/ros/cfg/Mapping.cfg)

catkin_package(
  INCLUDE_DIRS include
  LIBRARIES evidential_octomap
  CATKIN_DEPENDS message_runtime std_msgs geometry_msgs
  DEPENDS OCTOMAP)
