// One topic the node derives from its map, with its own "older than the map" flag: it is rebuilt
// only when the flag is set and someone listens (or when forced), so a subscriber that arrives
// late gets a fresh copy and a topic nobody listens to costs nothing.
#pragma once

#include <ros/ros.h>

namespace evidential_octomap {

struct StaleOutput {
  ros::Publisher publisher;
  bool stale = true;

  bool wanted(bool force) const { return stale && (force || publisher.getNumSubscribers() > 0); }
  template <typename Message>
  void send(const Message& message) {
    publisher.publish(message);
    stale = false;
  }
};

}  // namespace evidential_octomap
