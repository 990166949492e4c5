# ROS 1 part, stage 1 (included by the top-level CMakeLists.txt before the core library):
# find catkin and the ROS packages the node uses, generate messages/services, declare the package.
# Stage 2 (node, tests, install rules) is src/ros/CMakeLists.txt, added after the core library.

set(EVIDENTIAL_OCTOMAP_CATKIN_COMPONENTS
  roscpp roslib std_msgs std_srvs sensor_msgs geometry_msgs visualization_msgs diagnostic_msgs
  nav_msgs
  tf2 tf2_ros message_filters cv_bridge dynamic_reconfigure nodelet pluginlib)

find_package(catkin REQUIRED COMPONENTS message_generation ${EVIDENTIAL_OCTOMAP_CATKIN_COMPONENTS})

# octomap_msgs is optional: ROS distributions ship it (ros-<distro>-octomap-msgs), Debian does
# not. Found -> the node has octomap_server's octomap_binary / octomap_full topics and services;
# absent -> they are left out (the node says so at start-up), never a build failure.
find_package(octomap_msgs QUIET)
if(octomap_msgs_FOUND)
  message(STATUS "evidential_octomap: octomap_msgs found (${octomap_msgs_DIR}): "
    "octomap_binary / octomap_full topics and services are built")
else()
  message(STATUS "evidential_octomap: octomap_msgs not found: building without the "
    "octomap_binary / octomap_full topics and services (install your distribution's "
    "octomap_msgs, or put the package in the workspace, to get them)")
endif()

add_message_files(DIRECTORY msg FILES
  EvidentialMap.msg
  MappingStatus.msg
  OccupancyMap.msg)
add_service_files(DIRECTORY srv FILES
  BoundingBoxQuery.srv
  ClearBbx.srv
  LoadMap.srv
  QueryMap.srv
  SaveMap.srv)
generate_messages(DEPENDENCIES std_msgs geometry_msgs)

# Run-time parameters: dynamic_reconfigure's C++ server and cfg generator are in
# Debian's libdynamic-reconfigure-config-init-mutex-dev / python3-dynamic-reconfigure.
generate_dynamic_reconfigure_options(src/ros/cfg/Mapping.cfg)

catkin_package(
  INCLUDE_DIRS include
  LIBRARIES evidential_octomap  # the map only; evaluation and evidence are linked by name
  CATKIN_DEPENDS message_runtime std_msgs geometry_msgs
  DEPENDS OCTOMAP)
