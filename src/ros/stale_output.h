// One topic the node derives from its map, with its own "older than the map" flag: it is rebuilt
// only when the flag is set and someone listens (or when forced), so a subscriber that arrives
// late gets a fresh copy and a topic nobody listens to costs nothing.
#pragma once

#include <ros/ros.h>

#include <functional>
#include <vector>

namespace evidential_octomap {

struct StaleOutput {
  ros::Publisher publisher;
  bool stale = true;  // under the map lock

  bool wanted(bool force) const { return stale && (force || publisher.getNumSubscribers() > 0); }
  // Under the map lock, when the message is built from the map: a later change marks it stale
  // again, even while this message is still being sent.
  void claim() { stale = false; }
};

// Sends prepared while the map lock is held and run after it is released, so serialising and
// sending never holds up an insert.
using Outbox = std::vector<std::function<void()>>;

}  // namespace evidential_octomap
