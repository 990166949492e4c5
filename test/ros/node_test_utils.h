// Helpers shared by the rostests of the live node: clouds with one-hot evidence, points, and a
// spin loop with a hang guard (never a timing assertion).
#pragma once

#include <geometry_msgs/Point.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "evidential_octomap/QueryMap.h"

namespace node_test {

// The node under test and the SemanticKITTI class table its launch files load.
inline const std::string kNode = "/evidential_mapping_node";
constexpr int kClasses = 20;
constexpr int kRoad = 9;
constexpr int kBuilding = 13;  // colour (255, 200, 0)
constexpr int kPole = 18;

// One point of a synthetic scene and its class.
struct Point {
  float x, y, z;
  int cls;
};

// x, y, z, evidence[count] (float32); one-hot evidence of 30 on each point's class (none when
// the class is >= count).
inline sensor_msgs::PointCloud2 cloudOf(const std::vector<Point>& pts, const std::string& frame,
                                        int count) {
  using sensor_msgs::PointField;
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = frame;
  msg.header.stamp = ros::Time::now();
  const char* axes[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    PointField f;
    f.name = axes[i];
    f.offset = 4 * i;
    f.datatype = PointField::FLOAT32;
    f.count = 1;
    msg.fields.push_back(f);
  }
  PointField e;
  e.name = "evidence";
  e.offset = 12;
  e.datatype = PointField::FLOAT32;
  e.count = count;
  msg.fields.push_back(e);
  msg.point_step = 12 + 4 * count;
  msg.height = 1;
  msg.width = pts.size();
  msg.row_step = msg.point_step * msg.width;
  msg.is_dense = true;
  msg.data.assign(msg.row_step, 0);
  for (size_t i = 0; i < pts.size(); ++i) {
    uint8_t* p = msg.data.data() + i * msg.point_step;
    const float xyz[3] = {pts[i].x, pts[i].y, pts[i].z};
    std::memcpy(p, xyz, 12);
    if (pts[i].cls < count) {
      const float ev = 30.f;
      std::memcpy(p + 12 + 4 * pts[i].cls, &ev, 4);
    }
  }
  return msg;
}

// A vertical wall of `cls` at x, spanning [y0, y1] x [z0, z1] with the given point spacing.
inline std::vector<Point> wall(float x, float y0, float y1, float z0, float z1, float step,
                               int cls) {
  std::vector<Point> pts;
  for (float y = y0; y <= y1; y += step)
    for (float z = z0; z <= z1; z += step) pts.push_back({x, y, z, cls});
  return pts;
}

inline geometry_msgs::Point gp(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

// The tests' sensor: frame "lidar" at (1, 0, 0) in "map", static.
inline void sendLidarTransform(tf2_ros::StaticTransformBroadcaster* broadcaster) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time(0);
  t.header.frame_id = "map";
  t.child_frame_id = "lidar";
  t.transform.translation.x = 1.0;
  t.transform.rotation.w = 1.0;
  broadcaster->sendTransform(t);
}

// Spins until `done` holds; false after `timeout_s` (a hang guard, not a timing assertion).
inline bool waitFor(const std::function<bool()>& done, double timeout_s = 60.0) {
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < give_up) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return false;
}

// Calls the ~query service of `server` (a failed call fails the test and answers nothing).
inline evidential_octomap::QueryMap::Response queryNode(
    const std::string& server, const std::vector<geometry_msgs::Point>& points) {
  evidential_octomap::QueryMap srv;
  srv.request.points = points;
  EXPECT_TRUE(ros::service::call(server + "/query", srv));
  return srv.response;
}

// Label, occupancy and uncertainty of every point of the grid x0:dx:x1 * y0:dy:y1 * z0:dz:z1,
// flattened: what a test compares before and after an event that must not change the map.
inline std::vector<float> snapshotGrid(const std::string& server, double x0, double x1, double dx,
                                       double y0, double y1, double dy, double z0, double z1,
                                       double dz) {
  std::vector<geometry_msgs::Point> pts;
  for (double x = x0; x <= x1; x += dx)
    for (double y = y0; y <= y1; y += dy)
      for (double z = z0; z <= z1; z += dz) pts.push_back(gp(x, y, z));
  const auto r = queryNode(server, pts);
  std::vector<float> s;
  for (size_t i = 0; i < r.labels.size(); ++i) {
    s.insert(s.end(), {float(r.labels[i]), r.occupancy[i], r.uncertainties[i]});
  }
  return s;
}

}  // namespace node_test
