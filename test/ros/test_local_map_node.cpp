// rostest: a node with a local map (~local_map/radius) moves tiles to disk behind the sensor and
// reads them back on the way home; its ~query answers from the tiles on disk and its save_map
// writes the whole map, equal node for node to the map of a node that kept everything in memory
// (same clouds, same poses).
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cmath>
#include <cstdio>
#include <unistd.h>
#include <string>
#include <vector>

#include "evidential_octomap/MappingStatus.h"
#include "evidential_octomap/SaveMap.h"
#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/io.h"
#include "node_test_utils.h"
#include "tree_compare.h"

namespace eo = evidential_octomap;
using namespace node_test;

namespace {

// Ground (road) around the sensor out to 9 m and walls (building) 5 m to each side, in the
// sensor frame; the sensor is 1.6 m above the ground.
std::vector<Point> scene() {
  std::vector<Point> pts;
  for (float r = 1.0f; r <= 9.0f; r += 0.25f)
    for (float a = 0.0f; a < 6.2832f; a += 0.05f)
      pts.push_back({r * std::cos(a), r * std::sin(a), -1.5f, kRoad});
  for (float side : {-5.1f, 5.1f})
    for (float x = -6.0f; x <= 6.0f; x += 0.2f)
      for (float z = -1.4f; z <= 1.0f; z += 0.2f) pts.push_back({x, side, z, kBuilding});
  return pts;
}

struct Status {
  eo::MappingStatusConstPtr last;
  void keep(const eo::MappingStatusConstPtr& s) { last = s; }
  uint64_t inserted() const { return last ? last->clouds_inserted : 0; }
};

std::unique_ptr<eo::EvidentialOcTree> savedMap(const std::string& node, const std::string& path) {
  eo::SaveMap srv;
  srv.request.path = path;
  EXPECT_TRUE(ros::service::call("/" + node + "/save_map", srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  auto tree = eo::loadMap(path);
  eo::detail::TreeEditing::updateInnerNodes(*tree);  // both fully pruned before comparing
  std::remove(path.c_str());
  return tree;
}

TEST(LocalMapNode, SavedMapEqualsTheMapOfANodeWithoutTiles) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("cloud_in", 200);
  Status whole, local;
  ros::Subscriber s1 = nh.subscribe("/whole/status", 10, &Status::keep, &whole);
  ros::Subscriber s2 = nh.subscribe("/local/status", 10, &Status::keep, &local);
  ASSERT_TRUE(ros::service::waitForService("/whole/save_map", ros::Duration(60)));
  ASSERT_TRUE(ros::service::waitForService("/local/save_map", ros::Duration(60)));
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() >= 2 && whole.last && local.last; }));

  // One static frame per scan (lidar_<i> at the scan's pose): no TF timing in the test.
  tf2_ros::StaticTransformBroadcaster tf;
  std::vector<double> xs;
  for (int x = 0; x <= 60; x += 2) xs.push_back(x);
  for (int x = 58; x >= 0; x -= 2) xs.push_back(x);
  for (size_t i = 0; i < xs.size(); ++i) {
    geometry_msgs::TransformStamped t;
    t.header.frame_id = "map";
    t.child_frame_id = "lidar_" + std::to_string(i);
    t.transform.translation.x = xs[i];
    t.transform.translation.z = 1.6;
    t.transform.rotation.w = 1.0;
    tf.sendTransform(t);
  }
  const std::vector<Point> pts = scene();
  for (size_t i = 0; i < xs.size(); ++i) {
    // Each cloud once both nodes hold the one before: the same clouds in the same order.
    pub.publish(cloudOf(pts, "lidar_" + std::to_string(i), kClasses));
    ASSERT_TRUE(waitFor([&] { return whole.inserted() > i && local.inserted() > i; }))
        << "scan " << i << " not inserted by both nodes";
  }
  EXPECT_GT(local.last->local_map_tiles_written, 4u);
  EXPECT_GT(local.last->local_map_tiles_read, 0u);  // the way back read tiles again
  EXPECT_EQ(whole.last->local_map_tiles_written, 0u);
  EXPECT_LT(local.last->map_leaves, whole.last->map_leaves);  // less in memory

  // ~query far from the sensor (back at x = 0) reads the tiles on disk: the answers of a node
  // that kept everything. Grid over the far end of the path: ground, walls, free space.
  ASSERT_GT(local.last->local_map_tiles_on_disk, 0u);
  const auto far_whole = snapshotGrid("/whole", 40.0, 66.0, 0.5, -5.5, 5.5, 0.5, 0.2, 2.2, 0.5);
  const auto far_local = snapshotGrid("/local", 40.0, 66.0, 0.5, -5.5, 5.5, 0.5, 0.2, 2.2, 0.5);
  size_t labelled = 0;
  for (size_t i = 0; i < far_whole.size(); i += 3) labelled += far_whole[i] >= 0.f;
  EXPECT_GT(labelled, 200u);
  EXPECT_EQ(far_local, far_whole);

  const auto a = savedMap("whole", "/tmp/local_map_test_whole_" + std::to_string(::getpid()) + ".ot");
  const auto b = savedMap("local", "/tmp/local_map_test_local_" + std::to_string(::getpid()) + ".ot");
  ASSERT_TRUE(a && b);
  EXPECT_TRUE(eo::test::compareTrees(*a, *b));
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_local_map_node");
  return RUN_ALL_TESTS();
}
