// rostest: the real node's input and output accounting on a real roscore.
//  - Late subscribers: after mapping has ended, each view subscribed one after the other (as a
//    user ticks rviz displays or runs `rostopic echo`) still arrives, with the map in it.
//  - No silent drops: a burst of clouds faster than the insertion thread is either inserted or
//    counted as dropped, cloud for cloud; the node warns, ~status and /diagnostics say so, and
//    the newest cloud is the one that gets mapped.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>
#ifdef EVIDENTIAL_OCTOMAP_HAVE_OCTOMAP_MSGS
#include <octomap_msgs/Octomap.h>
#endif

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "evidential_octomap/EvidentialMap.h"
#include "evidential_octomap/MappingStatus.h"
#include "evidential_octomap/OccupancyMap.h"
#include "evidential_octomap/QueryMap.h"
#include "node_test_utils.h"

namespace eo = evidential_octomap;
using namespace node_test;

namespace {


class NodeIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("cloud_in", 20);
    status_sub_ = nh_.subscribe(kNode + "/status", 10, &NodeIoTest::onStatus, this);
    node_test::sendLidarTransform(&tf_);
    ASSERT_TRUE(ros::service::waitForService(kNode + "/query", ros::Duration(60)));
    ASSERT_TRUE(waitFor([&] { return cloud_pub_.getNumSubscribers() > 0 && status_; }));
  }

  void onStatus(const eo::MappingStatusConstPtr& s) { status_ = s; }

  // Waits until every cloud the node received has been inserted or dropped.
  bool waitUntilIdle(uint64_t received) {
    return waitFor([&] {
      return status_ && status_->clouds_received >= received && status_->queue_length == 0 &&
             status_->clouds_inserted + status_->clouds_dropped_queue +
                     status_->clouds_dropped_invalid ==
                 status_->clouds_received;
    });
  }

  int labelAt(double x, double y, double z) {
    eo::QueryMap srv;
    srv.request.points = {gp(x, y, z)};
    EXPECT_TRUE(ros::service::call(kNode + "/query", srv));
    return srv.response.labels.empty() ? -2 : srv.response.labels[0];
  }

  ros::NodeHandle nh_;
  ros::Publisher cloud_pub_;
  ros::Subscriber status_sub_;
  tf2_ros::StaticTransformBroadcaster tf_;
  eo::MappingStatusConstPtr status_;
};

// Subscribes to `topic` and waits for a message for which `holds_map` is true.
template <typename Message>
void expectReceived(ros::NodeHandle& nh, const std::string& topic,
                    const std::function<bool(const Message&)>& holds_map) {
  bool got = false;
  ros::Subscriber sub = nh.subscribe<Message>(
      topic, 1, [&](const boost::shared_ptr<const Message>& m) { got = got || holds_map(*m); });
  EXPECT_TRUE(waitFor([&] { return got; })) << topic << ": no map after mapping ended";
}

size_t cubes(const visualization_msgs::MarkerArray& a) {
  size_t n = 0;
  for (const auto& m : a.markers) n += m.points.size();
  return n;
}

}  // namespace

TEST_F(NodeIoTest, LateSubscribersGetEveryView) {
  const uint64_t before = status_->clouds_received;
  cloud_pub_.publish(node_test::cloudOf(
      node_test::wall(4.05f, -2.f, 2.f, 0.f, 1.5f, 0.05f, kBuilding), "lidar", kClasses));
  ASSERT_TRUE(waitUntilIdle(before + 1));
  ASSERT_EQ(labelAt(5.05, 0.0, 0.75), kBuilding);
  // Mapping has ended. A view subscribed now, then the next, and so on (as a user ticks rviz
  // displays one by one): each one arrives holding the wall (over 100 voxels).
  using visualization_msgs::MarkerArray;
  auto many_cubes = [](const MarkerArray& a) { return cubes(a) > 100; };
  auto many_points = [](const sensor_msgs::PointCloud2& c) { return c.width * c.height > 100; };
  expectReceived<MarkerArray>(nh_, "occupied_cells_vis_array", many_cubes);
  expectReceived<MarkerArray>(nh_, "uncertainty_cells_vis_array", many_cubes);
  expectReceived<sensor_msgs::PointCloud2>(nh_, "semantic_cloud", many_points);
  expectReceived<sensor_msgs::PointCloud2>(nh_, "octomap_point_cloud_centers", many_points);
  expectReceived<eo::EvidentialMap>(nh_, "evidential_map", [](const eo::EvidentialMap& m) {
    return m.num_classes == kClasses && m.data.size() > 4000;
  });
  expectReceived<eo::OccupancyMap>(nh_, "occupancy_map",
                                   [](const eo::OccupancyMap& m) { return m.data.size() > 400; });
  expectReceived<MarkerArray>(nh_, "conflict_cells_vis_array", many_cubes);
  expectReceived<MarkerArray>(nh_, "free_cells_vis_array", many_cubes);
  expectReceived<nav_msgs::OccupancyGrid>(
      nh_, "projected_map", [](const nav_msgs::OccupancyGrid& g) {
        return std::count(g.data.begin(), g.data.end(), 100) > 10;
      });
  expectReceived<sensor_msgs::Image>(nh_, kNode + "/legend",
                                     [](const sensor_msgs::Image& i) { return i.height > 100; });
#ifdef EVIDENTIAL_OCTOMAP_HAVE_OCTOMAP_MSGS
  for (const char* topic : {"octomap_binary", "octomap_full", "evidential_octomap_full"})
    expectReceived<octomap_msgs::Octomap>(
        nh_, topic, [](const octomap_msgs::Octomap& m) { return m.data.size() > 100; });
#endif
}

TEST_F(NodeIoTest, EveryCloudOfABurstIsInsertedOrCountedAsDropped) {
  std::vector<std::string> warnings;
  ros::Subscriber rosout =
      nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::LogConstPtr& m) {
        if (m->name == kNode && m->level == rosgraph_msgs::Log::WARN) warnings.push_back(m->msg);
      });
  bool diagnosed_warn = false;
  ros::Subscriber diagnostics = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& a) {
        for (const auto& s : a->status)
          if (s.hardware_id == kNode && s.level == diagnostic_msgs::DiagnosticStatus::WARN &&
              s.message.find("insertion queue full") != std::string::npos)
            diagnosed_warn = true;
      });
  // /rosout is not latched: see one of the node's own lines (a reset) before the burst.
  bool connected = false;
  ros::Subscriber hello =
      nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::LogConstPtr& m) {
        connected = connected || (m->name == kNode && m->msg.find("reset:") == 0);
      });
  ASSERT_TRUE(waitFor([&] {
    std_srvs::Empty reset;
    ros::service::call(kNode + "/reset", reset);
    return waitFor([&] { return connected; }, 0.5);
  }));
  const eo::MappingStatus start = *status_;

  // Ten clouds at once, each costly to insert (40k points, one per voxel, on a wall 40 m away:
  // 40k rays of 200 voxels), so the burst arrives long before the first insert ends; the
  // insertion queue holds one cloud, so most of the burst cannot be inserted. The last cloud has
  // its own wall (pole class, off to the side) so that the map shows whether it was kept.
  constexpr int kBurst = 10;
  const auto far = node_test::cloudOf(
      node_test::wall(40.05f, -40.f, 40.f, -2.f, 18.f, 0.2f, kBuilding), "lidar", kClasses);
  const auto last =
      node_test::cloudOf(node_test::wall(20.05f, 8.f, 10.f, 0.f, 1.f, 0.05f, kPole), "lidar", kClasses);
  for (int i = 0; i < kBurst; ++i) {
    auto msg = i + 1 < kBurst ? far : last;
    msg.header.stamp = ros::Time::now();
    cloud_pub_.publish(msg);
  }
  ASSERT_TRUE(waitUntilIdle(start.clouds_received + kBurst));
  const uint64_t inserted = status_->clouds_inserted - start.clouds_inserted;
  const uint64_t dropped = status_->clouds_dropped_queue - start.clouds_dropped_queue;
  EXPECT_EQ(status_->clouds_received - start.clouds_received, uint64_t(kBurst));
  EXPECT_EQ(inserted + dropped, uint64_t(kBurst)) << "a cloud went missing without a count";
  EXPECT_GE(dropped, 1u);
  EXPECT_GT(status_->last_insert_ms, 0.0);
  EXPECT_GT(status_->map_leaves, 0u);
  EXPECT_EQ(status_->queue_capacity, 1u);
  // The newest cloud is never the one dropped.
  EXPECT_EQ(labelAt(21.05, 9.0, 0.5), kPole);
  // Told in the log and on /diagnostics.
  EXPECT_TRUE(waitFor([&] {
    for (const auto& w : warnings)
      if (w.find("insertion is behind the input") != std::string::npos) return true;
    return false;
  })) << "no warning about the dropped clouds";
  EXPECT_TRUE(waitFor([&] { return diagnosed_warn; })) << "no WARN on /diagnostics";
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_io");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
