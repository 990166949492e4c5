// rostest: the node as a drop-in for octomap_server users, on a real roscore. The node starts
// from a plain OctoMap .bt (~map_file, test/fixtures/octomap_server_wall.bt: a wall at
// x = 12.05 seen from (1, 0, 0.5)), filters input heights in ~base_frame_id, limits its views and
// 2-D maps to occupancy_min_z..max_z, publishes projected_map and the per-class
// projected_cost_map, names classes in ~query, resolves relative save_map paths, and (built with
// octomap_msgs) serves octomap_binary / octomap_full and clear_bbx as octomap_msgs types.
#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <octomap/OcTree.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <unistd.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "evidential_octomap/MappingStatus.h"
#include "evidential_octomap/QueryMap.h"
#include "evidential_octomap/SaveMap.h"
#include "node_test_utils.h"

#ifdef EVIDENTIAL_OCTOMAP_HAVE_OCTOMAP_MSGS
#include <octomap/ColorOcTree.h>
#include <octomap_msgs/BoundingBoxQuery.h>
#include <octomap_msgs/GetOctomap.h>
#include <octomap_msgs/conversions.h>
#endif

namespace eo = evidential_octomap;
using namespace node_test;

namespace {


// Parameters of octomap_server_parity.test.
constexpr double kOccupancyMaxZ = 1.0, kOccupancyMinZ = -2.0;
constexpr int kCostOfOtherClasses = 60;

class ParityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("cloud_in", 5);
    status_sub_ = nh_.subscribe<eo::MappingStatus>(
        kNode + "/status", 10, [this](const eo::MappingStatusConstPtr& s) { status_ = s; });
    node_test::sendLidarTransform(&tf_);   // lidar at (1, 0, 0) in map
    geometry_msgs::TransformStamped base;  // base 1 m above the map origin
    base.header.frame_id = "map";
    base.child_frame_id = "base";
    base.transform.translation.z = 1.0;
    base.transform.rotation.w = 1.0;
    base_tf_.sendTransform(base);
    ASSERT_TRUE(ros::service::waitForService(kNode + "/query", ros::Duration(60)));
    ASSERT_TRUE(waitFor([&] { return cloud_pub_.getNumSubscribers() > 0 && status_; }));
    insertScene();
  }

  // In the lidar frame: a building wall at x = 4.05 (map 5.05), y in [-1, 1], map z from -0.5 to
  // 1.9, and a road patch at map z = -1.6. The node keeps base z in [-3, 0.3], map z in
  // [-2, 1.3]: the wall above 1.3 m never reaches the map.
  void insertScene() {
    auto pts = node_test::wall(4.05f, -1.f, 1.f, -0.5f, 1.9f, 0.05f, kBuilding);
    for (float x = 1.f; x <= 2.f; x += 0.05f)
      for (float y = -1.f; y <= 1.f; y += 0.05f) pts.push_back({x, y, -1.6f, kRoad});
    const uint64_t before = status_->clouds_inserted;
    cloud_pub_.publish(node_test::cloudOf(pts, "lidar", kClasses));
    ASSERT_TRUE(waitFor([&] { return status_->clouds_inserted > before; }));
  }

  eo::QueryMap::Response query(double x, double y, double z) {
    eo::QueryMap srv;
    srv.request.points = {gp(x, y, z)};
    EXPECT_TRUE(ros::service::call(kNode + "/query", srv));
    return srv.response;
  }

  template <typename Message>
  boost::shared_ptr<const Message> receive(const std::string& topic) {
    boost::shared_ptr<const Message> got;
    ros::Subscriber sub = nh_.subscribe<Message>(
        topic, 1, [&](const boost::shared_ptr<const Message>& m) { got = m; });
    EXPECT_TRUE(waitFor([&] { return bool(got); })) << "nothing on " << topic;
    return got;
  }

  ros::NodeHandle nh_;
  ros::Publisher cloud_pub_;
  ros::Subscriber status_sub_;
  tf2_ros::StaticTransformBroadcaster tf_, base_tf_;
  eo::MappingStatusConstPtr status_;
};

int cellAt(const nav_msgs::OccupancyGrid& grid, double x, double y) {
  const int i = int(std::floor((x - grid.info.origin.position.x) / grid.info.resolution));
  const int j = int(std::floor((y - grid.info.origin.position.y) / grid.info.resolution));
  if (i < 0 || j < 0 || i >= int(grid.info.width) || j >= int(grid.info.height)) return -2;
  return grid.data[j * grid.info.width + i];
}

}  // namespace

TEST_F(ParityTest, MapFileIsLoadedAtStartUp) {
  const auto wall = query(12.05, 0.0, 0.75);  // the .bt's wall: occupied, no evidence
  EXPECT_GT(wall.occupancy[0], 0.5f);
  EXPECT_EQ(wall.labels[0], -1);
  EXPECT_EQ(wall.class_names[0], "");
  const auto free = query(9.05, 0.0, 0.55);  // on the .bt's rays
  EXPECT_GE(free.occupancy[0], 0.f);
  EXPECT_LT(free.occupancy[0], 0.5f);
}

TEST_F(ParityTest, PointcloudHeightsAreFilteredInTheBaseFrame) {
  const auto kept = query(5.05, 0.0, 1.05);  // map z 1.05 = base z 0.05 <= 0.3
  EXPECT_EQ(kept.labels[0], kBuilding);
  const auto gone = query(5.05, 0.0, 1.65);  // base z 0.65 > 0.3: never inserted
  EXPECT_EQ(gone.labels[0], -1);
  EXPECT_FLOAT_EQ(gone.occupancy[0], -1.f);
}

TEST_F(ParityTest, QueryNamesTheClassAndGivesTheConflict) {
  const auto r = query(5.05, 0.0, 0.55);
  ASSERT_EQ(r.class_names.size(), 1u);
  EXPECT_EQ(r.labels[0], kBuilding);
  EXPECT_EQ(r.class_names[0], "building");
  ASSERT_EQ(r.conflicts.size(), 1u);
  EXPECT_GE(r.conflicts[0], 0.f);
  EXPECT_LT(r.conflicts[0], 1.f);
}

TEST_F(ParityTest, ViewsKeepToTheOccupancyHeights) {
  const auto markers = receive<visualization_msgs::MarkerArray>("occupied_cells_vis_array");
  size_t cubes = 0;
  bool road = false;
  for (const auto& m : markers->markers)
    for (const auto& p : m.points) {
      ++cubes;
      EXPECT_LE(p.z, kOccupancyMaxZ + 1e-6);
      EXPECT_GE(p.z, kOccupancyMinZ - 1e-6);
      road = road || p.z < -1.0;
    }
  EXPECT_GT(cubes, 50u);
  EXPECT_TRUE(road);
  const auto free = receive<visualization_msgs::MarkerArray>("free_cells_vis_array");
  size_t free_cubes = 0;
  for (const auto& m : free->markers) free_cubes += m.points.size();
  EXPECT_GT(free_cubes, 50u);
}

TEST_F(ParityTest, ProjectedMapsShowWallsAndTheDrivableRoad) {
  const auto grid = receive<nav_msgs::OccupancyGrid>("projected_map");
  EXPECT_EQ(grid->header.frame_id, "map");
  EXPECT_EQ(cellAt(*grid, 5.05, 0.05), 100);   // our wall
  EXPECT_EQ(cellAt(*grid, 12.05, 0.05), 100);  // the .bt's wall
  EXPECT_EQ(cellAt(*grid, 2.55, 0.05), 100);   // the road is an obstacle to projected_map
  EXPECT_EQ(cellAt(*grid, 9.05, 0.05), 0);     // free
  const auto costs = receive<nav_msgs::OccupancyGrid>("projected_cost_map");
  EXPECT_EQ(cellAt(*costs, 5.05, 0.05), 100);                   // building: 100
  EXPECT_EQ(cellAt(*costs, 12.05, 0.05), kCostOfOtherClasses);  // no class: the default
  EXPECT_EQ(cellAt(*costs, 2.55, 0.05), 0);                     // road: 0, drivable
  EXPECT_EQ(cellAt(*costs, 9.05, 0.05), 0);
}

TEST_F(ParityTest, RelativeSaveMapPathIsResolvedAndReported) {
  const std::string name = "parity_relative_" + std::to_string(getpid());
  for (const std::string ext : {".ot", ".bt"}) {
    eo::SaveMap srv;
    srv.request.path = name + ext;
    ASSERT_TRUE(ros::service::call(kNode + "/save_map", srv));
    ASSERT_TRUE(srv.response.success) << srv.response.message;
    const std::string& path = srv.response.path;
    EXPECT_EQ(path.front(), '/') << path;
    EXPECT_EQ(path.substr(path.size() - name.size() - 3), name + ext);
    EXPECT_NE(srv.response.message.find(path), std::string::npos) << srv.response.message;
    if (ext == ".bt") {  // occupancy only, for stock tools
      octomap::OcTree plain(0.1);
      ASSERT_TRUE(plain.readBinary(path));
      const auto* node = plain.search(5.05, 0.0, 0.55);
      ASSERT_NE(node, nullptr);
      EXPECT_TRUE(plain.isNodeOccupied(node));
    }
    EXPECT_EQ(std::remove(path.c_str()), 0) << "no file at " << path;
  }
}

#ifdef EVIDENTIAL_OCTOMAP_HAVE_OCTOMAP_MSGS
TEST_F(ParityTest, OctomapServicesAndTopicsReadBackWithOctomapMsgs) {
  octomap_msgs::GetOctomap binary, full;
  ASSERT_TRUE(ros::service::call("octomap_binary", binary));
  ASSERT_TRUE(ros::service::call("octomap_full", full));
  std::unique_ptr<octomap::AbstractOcTree> a(octomap_msgs::msgToMap(binary.response.map));
  auto* plain = dynamic_cast<octomap::OcTree*>(a.get());
  ASSERT_NE(plain, nullptr);
  EXPECT_TRUE(plain->isNodeOccupied(plain->search(5.05, 0.0, 0.55)));
  EXPECT_TRUE(plain->isNodeOccupied(plain->search(12.05, 0.0, 0.75)));
  std::unique_ptr<octomap::AbstractOcTree> b(octomap_msgs::msgToMap(full.response.map));
  auto* color = dynamic_cast<octomap::ColorOcTree*>(b.get());
  ASSERT_NE(color, nullptr);
  const auto* wall = color->search(5.05, 0.0, 0.55);
  ASSERT_NE(wall, nullptr);
  EXPECT_EQ(wall->getColor(), octomap::ColorOcTreeNode::Color(255, 200, 0));  // building
  const auto topic = receive<octomap_msgs::Octomap>("octomap_binary");
  EXPECT_EQ(topic->id, "OcTree");
  EXPECT_EQ(receive<octomap_msgs::Octomap>("octomap_full")->id, "ColorOcTree");
  EXPECT_EQ(receive<octomap_msgs::Octomap>("evidential_octomap_full")->id, "EvidentialOcTree");
}

TEST_F(ParityTest, ClearBbxTakesAnOctomapMsgsBoundingBoxQuery) {
  octomap_msgs::BoundingBoxQuery srv;  // octomap_server's type, unchanged
  srv.request.min = gp(4.5, 0.5, -1.0);
  srv.request.max = gp(5.5, 1.5, 2.0);
  ASSERT_TRUE(ros::service::call(kNode + "/clear_bbx", srv));
  const auto inside = query(5.05, 0.75, 0.55), outside = query(5.05, -0.75, 0.55);
  EXPECT_EQ(inside.labels[0], -1);
  EXPECT_LT(inside.occupancy[0], 0.5f);
  EXPECT_EQ(outside.labels[0], kBuilding);
}
#endif

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_octomap_server_parity");
  ros::NodeHandle nh;
#ifndef EVIDENTIAL_OCTOMAP_HAVE_OCTOMAP_MSGS
  ROS_INFO("built without octomap_msgs: the octomap_binary / octomap_full tests are skipped");
#endif
  return RUN_ALL_TESTS();
}
