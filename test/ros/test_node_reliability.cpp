// rostest: requests and settings that used to hang, kill or silently damage the real
// node are refused with a clear answer, and the node goes on mapping and answering.
//  - ~clear_bbx with NaN or inverted boxes (a NaN max cleared the whole map);
//  - labels >= 2^31 (cast to int, mapped as occupancy-only points without a word);
//  - ~load_map on a FIFO (blocked the node until a writer came) and on /dev/zero;
//  - ~query with NaN and infinite points (undefined behaviour in OctoMap's search);
//  - a kernel of l = 5 m, beta = 10 (a 16-point cloud took 180 s and 3.3 GB; with large
//    evidence the node died of std::bad_alloc);
//  - sensor-model sliders at their ends (hit 1 gave a saved map that could not be loaded).
// Every wait is a hang guard (node_test::waitFor, 60 s), never a timing assertion.
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <sys/stat.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <future>
#include <limits>
#include <string>
#include <vector>

#include "evidential_octomap/BoundingBoxQuery.h"
#include "evidential_octomap/ClearBbx.h"
#include "evidential_octomap/LoadMap.h"
#include "evidential_octomap/MappingStatus.h"
#include "evidential_octomap/QueryMap.h"
#include "evidential_octomap/SaveMap.h"
#include "node_test_utils.h"
#include "ros_params.h"

namespace eo = evidential_octomap;
using node_test::gp;
using node_test::snapshotGrid;
using node_test::waitFor;

namespace {

constexpr int kC = 20;
constexpr int kBuilding = 13;
const std::string kNode = "/evidential_mapping_node";
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The wall of the other rostests: building class at map x = 5.05, y in [-2, 2], z in [0, 1.5].
sensor_msgs::PointCloud2 wallCloud() {
  return node_test::cloudOf(node_test::wall(4.05f, -2.f, 2.f, 0.f, 1.5f, 0.05f, kBuilding), "lidar",
                            kC);
}

// x, y, z (float32) and one `label` field of `datatype` holding `label` for every point.
template <typename T>
sensor_msgs::PointCloud2 labelCloud(uint8_t datatype, T label) {
  using sensor_msgs::PointField;
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = "lidar";
  msg.header.stamp = ros::Time::now();
  const char* names[4] = {"x", "y", "z", "label"};
  for (int i = 0; i < 4; ++i) {
    PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = i < 3 ? PointField::FLOAT32 : datatype;
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.point_step = 12 + sizeof(T);
  const auto pts = node_test::wall(8.05f, -1.f, 1.f, 0.f, 1.f, 0.1f, 0);  // where the map is empty
  msg.height = 1;
  msg.width = pts.size();
  msg.row_step = msg.point_step * msg.width;
  msg.data.assign(msg.row_step, 0);
  for (size_t i = 0; i < pts.size(); ++i) {
    uint8_t* p = msg.data.data() + i * msg.point_step;
    const float xyz[3] = {pts[i].x, pts[i].y, pts[i].z};
    std::memcpy(p, xyz, 12);
    std::memcpy(p + 12, &label, sizeof(T));
  }
  return msg;
}

class NodeReliabilityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("cloud_in", 5);
    status_sub_ = nh_.subscribe(kNode + "/status", 10, &NodeReliabilityTest::onStatus, this);
    rosout_sub_ = nh_.subscribe("/rosout", 200, &NodeReliabilityTest::onLog, this);
    node_test::sendLidarTransform(&tf_);
    ASSERT_TRUE(ros::service::waitForService(kNode + "/query", ros::Duration(60)));
    ASSERT_TRUE(waitFor([&] { return cloud_pub_.getNumSubscribers() > 0 && status_; }));
    std_srvs::Empty reset;
    ASSERT_TRUE(ros::service::call(kNode + "/reset", reset));
  }

  void onStatus(const eo::MappingStatusConstPtr& s) { status_ = s; }
  void onLog(const rosgraph_msgs::LogConstPtr& m) {
    if (m->name == kNode) logs_.push_back(m->msg);
  }
  bool logSays(const std::string& text) {
    for (const auto& line : logs_)
      if (line.find(text) != std::string::npos) return true;
    return false;
  }

  int wallLabel() { return query({gp(5.05, 0.0, 0.75)}).labels.at(0); }

  // Publishes the wall and waits until the node has mapped it.
  void mapTheWall() {
    const uint64_t inserted = status_ ? status_->clouds_inserted : 0;
    cloud_pub_.publish(wallCloud());
    ASSERT_TRUE(waitFor([&] { return status_ && status_->clouds_inserted > inserted; }));
    ASSERT_EQ(wallLabel(), kBuilding);
  }

  eo::QueryMap::Response query(const std::vector<geometry_msgs::Point>& points) {
    return node_test::queryNode(kNode, points);
  }

  // Label, occupancy and uncertainty on a grid over the wall and the empty space behind it.
  std::vector<float> snapshot() {
    return snapshotGrid(kNode, 3.0, 9.0, 0.2, -2.5, 2.5, 0.25, -0.2, 1.6, 0.3);
  }

  // Calls a service from another thread: a call that never returns fails the test instead of
  // stalling it (what ~load_map did on a FIFO).
  template <typename Service>
  bool callWithGuard(const std::string& name, Service* srv) {
    auto call = std::async(std::launch::async, [&] { return ros::service::call(name, *srv); });
    if (call.wait_for(std::chrono::seconds(60)) != std::future_status::ready) {
      ADD_FAILURE() << name << " did not return within 60 s";
      std::quick_exit(1);  // the blocked call cannot be cancelled
    }
    return call.get();
  }

  ros::NodeHandle nh_;
  ros::Publisher cloud_pub_;
  ros::Subscriber status_sub_, rosout_sub_;
  tf2_ros::StaticTransformBroadcaster tf_;
  eo::MappingStatusConstPtr status_;
  std::vector<std::string> logs_;
};

// Sets doubles through dynamic_reconfigure; returns the configuration the server answers with.
dynamic_reconfigure::Config setDoubles(const std::vector<std::pair<std::string, double>>& values) {
  dynamic_reconfigure::Reconfigure srv;
  for (const auto& [name, value] : values) {
    dynamic_reconfigure::DoubleParameter p;
    p.name = name;
    p.value = value;
    srv.request.config.doubles.push_back(p);
  }
  EXPECT_TRUE(ros::service::call(kNode + "/set_parameters", srv));
  return srv.response.config;
}

double valueOf(const dynamic_reconfigure::Config& config, const std::string& name) {
  for (const auto& d : config.doubles)
    if (d.name == name) return d.value;
  ADD_FAILURE() << name << " not in the server's answer";
  return kNaN;
}

}  // namespace

TEST_F(NodeReliabilityTest, ClearBbxRefusesNonFiniteAndInvertedBoxes) {
  mapTheWall();
  const auto before = snapshot();
  const std::pair<geometry_msgs::Point, geometry_msgs::Point> boxes[] = {
      {gp(4.0, -3.0, -1.0), gp(kNaN, kNaN, kNaN)},      // cleared the wall before
      {gp(-1000, -1000, -1000), gp(kNaN, 1000, 1000)},  // cleared the whole map before
      {gp(6.0, 3.0, 2.0), gp(4.0, -3.0, -1.0)},         // inverted
      {gp(4.0, -3.0, -1.0), gp(INFINITY, 3.0, 2.0)}};
  for (const auto& [min, max] : boxes) {
    eo::ClearBbx srv;  // ~clear_box replies with the reason
    srv.request.min = min;
    srv.request.max = max;
    ASSERT_TRUE(ros::service::call(kNode + "/clear_box", srv));
    EXPECT_FALSE(srv.response.success);
    EXPECT_NE(srv.response.message.find("refused"), std::string::npos) << srv.response.message;
    EXPECT_EQ(srv.response.voxels_cleared, 0u);
    eo::BoundingBoxQuery octomap_server_style;  // ~clear_bbx's reply is empty: the call fails
    octomap_server_style.request.min = min;
    octomap_server_style.request.max = max;
    EXPECT_FALSE(ros::service::call(kNode + "/clear_bbx", octomap_server_style));
  }
  EXPECT_EQ(snapshot(), before) << "a refused box changed the map";
  EXPECT_EQ(wallLabel(), kBuilding);
}

TEST_F(NodeReliabilityTest, LabelsBeyondIntAreRefusedCountedAndWarned) {
  mapTheWall();
  const auto before = snapshot();
  using sensor_msgs::PointField;
  // One at a time: the insertion queue holds one cloud, a burst would be dropped as such.
  for (const auto& cloud : {labelCloud<uint32_t>(PointField::UINT32, 4294967295u),
                            labelCloud<uint32_t>(PointField::UINT32, 2147483648u),
                            labelCloud<double>(PointField::FLOAT64, 1e300)}) {
    const uint64_t invalid = status_->clouds_dropped_invalid;
    cloud_pub_.publish(cloud);
    EXPECT_TRUE(waitFor([&] { return status_->clouds_dropped_invalid == invalid + 1; }))
        << "the cloud was not counted as refused";
  }
  EXPECT_TRUE(waitFor([&] { return logSays("is outside [0, 20)"); }));
  EXPECT_EQ(snapshot(), before) << "a cloud with labels beyond C changed the map";
}

TEST_F(NodeReliabilityTest, LoadMapRefusesFifosAndDevicesAndTheNodeGoesOn) {
  mapTheWall();
  const std::string fifo = "/tmp/evidential_reliability_fifo_" + std::to_string(getpid());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& path : {fifo, std::string("/dev/zero"), std::string("/tmp")}) {
    eo::LoadMap srv;
    srv.request.path = path;
    ASSERT_TRUE(callWithGuard(kNode + "/load_map", &srv)) << path;
    EXPECT_FALSE(srv.response.success) << path;
    EXPECT_NE(srv.response.message.find("not a regular file"), std::string::npos)
        << srv.response.message;
  }
  std::remove(fifo.c_str());
  EXPECT_EQ(wallLabel(), kBuilding) << "the map changed";
  mapTheWall();  // and the node still maps
}

TEST_F(NodeReliabilityTest, QueryOfNonFinitePointsAnswersUnknown) {
  mapTheWall();
  const auto r = query({gp(kNaN, 0, 0), gp(5.05, kNaN, 0.75), gp(INFINITY, 0, 0),
                        gp(-INFINITY, -INFINITY, -INFINITY), gp(1e30, 0, 0), gp(5.05, 0, 0.75)});
  ASSERT_EQ(r.labels.size(), 6u);
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(r.labels[i], -1) << i;
    EXPECT_FLOAT_EQ(r.occupancy[i], -1.f) << i;
    EXPECT_FLOAT_EQ(r.uncertainties[i], 1.f) << i;
  }
  EXPECT_EQ(r.labels[5], kBuilding);
}

TEST_F(NodeReliabilityTest, UnaffordableKernelIsRefusedAndMappingGoesOn) {
  const auto config = setDoubles({{"length_scale", 5.0}, {"beta", 10.0}});
  EXPECT_LT(valueOf(config, "length_scale") * valueOf(config, "beta"), 1.0)
      << "the server took the kernel (or did not answer with the values in use)";
  EXPECT_TRUE(waitFor([&] { return logSays("reconfigure refused"); }));
  // With the huge kernel a 16-point cloud took minutes; with the values in use it is mapped.
  mapTheWall();
}

TEST_F(NodeReliabilityTest, WidestAffordableKernelWithLabelEvidence1000MapsAndGoesOn) {
  // Issue 16 item 4: label_evidence 1000 (the slider's end) makes every labelled point certain,
  // so each reaches the kernel's widest support; with a kernel inside the old ranges the node
  // died of std::bad_alloc. The widest kernel the bound admits (l * beta * e = 1.90 m, 9.5
  // leaves at 0.2 m) with that evidence maps the wall and leaves the node answering.
  const auto in_use = setDoubles({});
  const auto config =
      setDoubles({{"label_evidence", 1000.0}, {"length_scale", 0.7}, {"beta", 1.0}});
  EXPECT_DOUBLE_EQ(valueOf(config, "label_evidence"), 1000.0);
  EXPECT_DOUBLE_EQ(valueOf(config, "length_scale"), 0.7) << "the bound refused a kernel it admits";
  mapTheWall();
  EXPECT_LT(query({gp(5.05, 0.0, 0.75)}).uncertainties.at(0), 0.1f);  // certain evidence
  setDoubles({{"label_evidence", valueOf(in_use, "label_evidence")},
              {"length_scale", valueOf(in_use, "length_scale")},
              {"beta", valueOf(in_use, "beta")}});
}

TEST_F(NodeReliabilityTest, SensorModelAtTheSliderEndsGivesAMapThatLoads) {
  // hit 1 and clamps 0 / 1 are outside the sliders: dynamic_reconfigure clamps them.
  auto config = setDoubles({{"sensor_model_hit", 1.0},
                            {"sensor_model_miss", 0.0},
                            {"sensor_model_min", 0.0},
                            {"sensor_model_max", 1.0}});
  EXPECT_LE(valueOf(config, "sensor_model_hit"), 0.999);
  EXPECT_GE(valueOf(config, "sensor_model_miss"), 0.001);
  EXPECT_GE(valueOf(config, "sensor_model_min"), 0.001);
  EXPECT_LE(valueOf(config, "sensor_model_max"), 0.999);
  // A clamp range that is empty is refused: the values in use stay.
  config = setDoubles({{"sensor_model_min", 0.6}, {"sensor_model_max", 0.4}});
  EXPECT_LT(valueOf(config, "sensor_model_min"), valueOf(config, "sensor_model_max"));
  mapTheWall();
  const std::string path = "/tmp/evidential_reliability_ends_" + std::to_string(getpid()) + ".ot";
  eo::SaveMap save;
  save.request.path = path;
  ASSERT_TRUE(ros::service::call(kNode + "/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  std_srvs::Empty reset;
  ASSERT_TRUE(ros::service::call(kNode + "/reset", reset));
  eo::LoadMap load;
  load.request.path = path;
  ASSERT_TRUE(ros::service::call(kNode + "/load_map", load));
  EXPECT_TRUE(load.response.success) << load.response.message;
  EXPECT_EQ(wallLabel(), kBuilding);
  std::remove(path.c_str());
  setDoubles({{"sensor_model_hit", 0.7},
              {"sensor_model_miss", 0.4},
              {"sensor_model_min", 0.12},
              {"sensor_model_max", 0.97}});
}

// ~params are read by the node's own functions (ros_params.h): out-of-range values stop the node
// at start-up with the parameter named, before any map exists.
TEST(NodeParameters, SensorModelAndKernelOutsideTheRangesAreRefused) {
  ros::NodeHandle sensor("~hit_one");
  sensor.setParam("sensor_model/hit", 1.0);
  eo::EvidentialOcTree tree(0.2, 3);
  try {
    eo::readOccupancyParams(sensor, &tree);
    ADD_FAILURE() << "~sensor_model/hit 1.0 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("hit = 1"), std::string::npos) << e.what();
  }
  ros::NodeHandle kernel("~huge_kernel");
  kernel.setParam("length_scale", 5.0);
  kernel.setParam("beta", 10.0);
  eo::SemanticConfig config;
  EXPECT_THROW(eo::readSemanticConfig(kernel, 0.2, &config), std::invalid_argument);
  ros::NodeHandle fine("~defaults");
  eo::SemanticConfig defaults;
  EXPECT_NO_THROW(eo::readSemanticConfig(fine, 0.2, &defaults));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_reliability");
  return RUN_ALL_TESTS();
}
