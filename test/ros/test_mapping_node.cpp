// rostest: the real evidential_mapping_node on a real roscore. Publishes clouds with evidence and
// a static TF, then checks the markers, the voxel cloud, every service, and that malformed
// clouds or missing TF leave the node alive, the map unchanged and a clear log line.
#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/BoundingBoxQuery.h"
#include "evidential_octomap/EvidentialMap.h"
#include "evidential_octomap/LoadMap.h"
#include "evidential_octomap/QueryMap.h"
#include "evidential_octomap/SaveMap.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "node_test_utils.h"

using sensor_msgs::PointField;
namespace eo = evidential_octomap;

namespace {

constexpr int kC = 20;         // SemanticKITTI table
constexpr int kBuilding = 13;  // colour (255, 200, 0)
constexpr int kRoad = 9;
// Where the server's services live and which node's /rosout lines are its log (a nodelet logs
// under its manager's name): ~server and ~log_node of the test node.
std::string kNode = "/evidential_mapping_node";
std::string kLogNode = kNode;

// The sensor sits at (1, 0, 0) in map; its clouds are in frame "lidar".
// Scene (sensor frame): a wall of class `wall_class` at x = 4 (map x = 5), y in [-2, 2],
// z in [0, 1.5]; a road patch at z = -1.6 in front of it.
using node_test::gp;
using node_test::Point;
using node_test::snapshotGrid;

std::vector<Point> scene(float wall_x = 4.05f, int wall_class = kBuilding) {
  std::vector<Point> pts = node_test::wall(wall_x, -2.f, 2.f, 0.f, 1.5f, 0.05f, wall_class);
  for (float x = 1.f; x <= 2.f; x += 0.05f)
    for (float y = -1.f; y <= 1.f; y += 0.05f) pts.push_back({x, y, -1.6f, kRoad});
  return pts;
}

sensor_msgs::PointCloud2 lidarCloud(const std::vector<Point>& pts,
                                    const std::string& frame = "lidar", int count = kC) {
  return node_test::cloudOf(pts, frame, count);
}

void setEvidence(sensor_msgs::PointCloud2* msg, size_t point, int cls, float value) {
  std::memcpy(msg->data.data() + point * msg->point_step + 12 + 4 * cls, &value, 4);
}

class MappingNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("cloud_in", 5);
    semantic_sub_ =
        nh_.subscribe("occupied_cells_vis_array", 1, &MappingNodeTest::onSemantic, this);
    uncertainty_sub_ =
        nh_.subscribe("uncertainty_cells_vis_array", 1, &MappingNodeTest::onUncertainty, this);
    cloud_sub_ = nh_.subscribe("semantic_cloud", 1, &MappingNodeTest::onCloud, this);
    rosout_sub_ = nh_.subscribe("/rosout", 100, &MappingNodeTest::onLog, this);
    node_test::sendLidarTransform(&tf_);
    ASSERT_TRUE(ros::service::waitForService(kNode + "/query", ros::Duration(60)));
    ASSERT_TRUE(waitFor([&] { return cloud_pub_.getNumSubscribers() > 0; }));
    ASSERT_TRUE(waitFor([&] {
      return semantic_sub_.getNumPublishers() > 0 && uncertainty_sub_.getNumPublishers() > 0 &&
             cloud_sub_.getNumPublishers() > 0;
    }));
    callReset();
    // Views sent before the reset may still be queued: wait until the empty ones are the latest,
    // so every view seen later comes from this test's scans.
    ASSERT_TRUE(waitFor([&] {
      return semantic_ && uncertainty_ && cloud_ && cubes(semantic_) == 0 &&
             cubes(uncertainty_) == 0 && cloud_->width == 0;
    }));
  }

  static size_t cubes(const visualization_msgs::MarkerArrayConstPtr& a) {
    size_t n = 0;
    if (a)
      for (const auto& m : a->markers) n += m.points.size();
    return n;
  }

  void onSemantic(const visualization_msgs::MarkerArrayConstPtr& m) { semantic_ = m; }
  void onUncertainty(const visualization_msgs::MarkerArrayConstPtr& m) { uncertainty_ = m; }
  void onCloud(const sensor_msgs::PointCloud2ConstPtr& m) { cloud_ = m; }
  void onLog(const rosgraph_msgs::LogConstPtr& m) {
    if (m->name == kLogNode) logs_.push_back(m->msg);
  }

  bool waitFor(const std::function<bool()>& done, double timeout_s = 60.0) {
    return node_test::waitFor(done, timeout_s);
  }

  bool logSays(const std::string& text) {
    for (const auto& line : logs_)
      if (line.find(text) != std::string::npos) return true;
    return false;
  }

  void callReset() {
    std_srvs::Empty srv;
    ASSERT_TRUE(ros::service::call(kNode + "/reset", srv));
  }

  // Publishes `cloud` and waits for the views it causes (the node publishes after every scan).
  void insert(const sensor_msgs::PointCloud2& cloud) {
    semantic_.reset();
    cloud_.reset();
    uncertainty_.reset();
    cloud_pub_.publish(cloud);
    ASSERT_TRUE(waitFor([&] {
      return cubes(semantic_) > 0 && cubes(uncertainty_) > 0 && cloud_ && cloud_->width > 0;
    }));
  }

  eo::QueryMap::Response query(const std::vector<geometry_msgs::Point>& points) {
    return node_test::queryNode(kNode, points);
  }

  // Label, occupancy and uncertainty on a grid covering the scene and the bad clouds' region.
  std::vector<float> snapshot() {
    return snapshotGrid(kNode, 0.0, 10.0, 0.2, -2.5, 2.5, 0.2, -1.8, 1.6, 0.2);
  }

  ros::NodeHandle nh_;
  ros::Publisher cloud_pub_;
  ros::Subscriber semantic_sub_, uncertainty_sub_, cloud_sub_, rosout_sub_;
  tf2_ros::StaticTransformBroadcaster tf_;
  visualization_msgs::MarkerArrayConstPtr semantic_, uncertainty_;
  sensor_msgs::PointCloud2ConstPtr cloud_;
  std::vector<std::string> logs_;
};

// Fields of the node's semantic_cloud as (x, y, z, label, u) rows.
struct VoxelRow {
  float x, y, z;
  int label;
  float u;
};
std::vector<VoxelRow> rowsOf(const sensor_msgs::PointCloud2& msg) {
  std::map<std::string, uint32_t> off;
  for (const auto& f : msg.fields) off[f.name] = f.offset;
  std::vector<VoxelRow> rows(msg.width * msg.height);
  for (size_t i = 0; i < rows.size(); ++i) {
    const uint8_t* p = msg.data.data() + i * msg.point_step;
    std::memcpy(&rows[i].x, p + off["x"], 4);
    std::memcpy(&rows[i].y, p + off["y"], 4);
    std::memcpy(&rows[i].z, p + off["z"], 4);
    std::memcpy(&rows[i].label, p + off["label"], 4);
    std::memcpy(&rows[i].u, p + off["uncertainty"], 4);
  }
  return rows;
}

bool onWall(float x, float y, float z) {
  return std::abs(x - 5.05f) < 0.25f && std::abs(y) < 1.8f && z > 0.2f && z < 1.3f;
}

}  // namespace

TEST_F(MappingNodeTest, SemanticMarkersShowTheWallInBuildingColour) {
  insert(lidarCloud(scene()));
  size_t wall_cubes = 0, building_coloured = 0, total = 0;
  for (const auto& m : semantic_->markers) {
    EXPECT_EQ(m.header.frame_id, "map");
    total += m.points.size();
    for (size_t i = 0; i < m.points.size(); ++i) {
      if (!onWall(m.points[i].x, m.points[i].y, m.points[i].z)) continue;
      ++wall_cubes;
      const auto& c = m.colors[i];
      if (std::abs(c.r - 1.f) < 1e-3 && std::abs(c.g - 200.f / 255.f) < 1e-3 && c.b < 1e-3)
        ++building_coloured;
    }
  }
  EXPECT_GT(total, 0u);
  ASSERT_GT(wall_cubes, 50u);
  EXPECT_EQ(building_coloured, wall_cubes);
  // The uncertainty view draws the same cubes.
  size_t total_u = 0;
  for (const auto& m : uncertainty_->markers) total_u += m.points.size();
  EXPECT_EQ(total_u, total);
}

TEST_F(MappingNodeTest, SemanticCloudCarriesClassAndFusedUncertainty) {
  const std::vector<Point> pts = scene();
  insert(lidarCloud(pts));
  // The same scan through the core library directly, with the same (default) parameters.
  eo::EvidentialOcTree reference(0.2, kC);
  octomap::Pointcloud points_S;
  std::vector<float> evidence;
  for (const auto& p : pts) {
    points_S.push_back(p.x, p.y, p.z);
    for (int c = 0; c < kC; ++c) evidence.push_back(c == p.cls ? 30.f : 0.f);
  }
  reference.insertSemanticScan(points_S, evidence, octomap::pose6d(1, 0, 0, 0, 0, 0));

  const auto rows = rowsOf(*cloud_);
  // The road lies at z = -1.6, a voxel boundary: its voxels are the layer OctoMap puts -1.6 in.
  const float road_z =
      reference.keyToCoord(reference.coordToKey(octomap::point3d(2.5f, 0.f, -1.6f))).z();
  size_t wall = 0, road = 0;
  for (const auto& r : rows) {
    const eo::VoxelOpinion expected = reference.query(octomap::point3d(r.x, r.y, r.z));
    EXPECT_EQ(r.label, expected.label);
    EXPECT_FLOAT_EQ(r.u, expected.uncertainty);
    if (onWall(r.x, r.y, r.z)) {
      ++wall;
      EXPECT_EQ(r.label, kBuilding);
      EXPECT_GT(r.u, 0.f);
      EXPECT_LT(r.u, 1.f);
    }
    if (std::abs(r.z - road_z) < 0.05f && r.x > 2.2f && r.x < 2.8f && std::abs(r.y) < 0.8f) {
      ++road;
      EXPECT_EQ(r.label, kRoad);
    }
  }
  EXPECT_GT(wall, 50u);
  EXPECT_GT(road, 10u);
}

TEST_F(MappingNodeTest, QueryReturnsClassBeliefsAndUnknown) {
  insert(lidarCloud(scene()));
  const auto r = query({gp(5.05, 0.0, 0.75), gp(50, 50, 50)});
  ASSERT_EQ(r.labels.size(), 2u);
  ASSERT_EQ(r.num_classes, kC);
  ASSERT_EQ(r.beliefs.size(), 2u * kC);
  EXPECT_EQ(r.labels[0], kBuilding);
  EXPECT_GT(r.occupancy[0], 0.5f);
  float sum = r.uncertainties[0];
  for (int c = 0; c < kC; ++c) {
    sum += r.beliefs[c];
    if (c != kBuilding) EXPECT_LT(r.beliefs[c], r.beliefs[kBuilding]);
  }
  EXPECT_NEAR(sum, 1.f, 1e-4);  // beliefs + u = 1 (Dempster rule)
  EXPECT_EQ(r.labels[1], -1);
  EXPECT_FLOAT_EQ(r.occupancy[1], -1.f);
  EXPECT_FLOAT_EQ(r.uncertainties[1], 1.f);
}

// calibrated_node.test loads an error model P(wrong) = sigmoid(0.5 + 2 ln u) (~calibrated set);
// without one the node answers 1 - max p, p = belief + u / C.
TEST_F(MappingNodeTest, QueryAnswersTheErrorProbabilityOfTheCalibration) {
  insert(lidarCloud(scene()));
  const auto r = query({gp(5.05, 0.0, 0.75)});
  ASSERT_EQ(r.error_probabilities.size(), 1u);
  ASSERT_EQ(r.labels[0], kBuilding);
  const float u = r.uncertainties[0];
  const float expected = ros::NodeHandle("~").param("calibrated", false)
                             ? 1.f / (1.f + std::exp(-(0.5f + 2.f * std::log(u))))
                             : 1.f - (r.beliefs[kBuilding] + u / kC);
  EXPECT_NEAR(r.error_probabilities[0], expected, 1e-4);
}

TEST_F(MappingNodeTest, SaveMapWritesAnOtThatReadsBackAsEvidentialOcTree) {
  insert(lidarCloud(scene()));
  const std::string path = "/tmp/evidential_octomap_rostest_" + std::to_string(getpid()) + ".ot";
  eo::SaveMap srv;
  srv.request.path = path;
  ASSERT_TRUE(ros::service::call(kNode + "/save_map", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(path));
  ASSERT_NE(read, nullptr);
  auto* tree = dynamic_cast<eo::EvidentialOcTree*>(read.get());
  ASSERT_NE(tree, nullptr) << read->getTreeType();
  EXPECT_EQ(tree->numClasses(), kC);
  EXPECT_EQ(tree->classNames()[kBuilding], "building");
  EXPECT_EQ(tree->query(octomap::point3d(5.05f, 0.f, 0.75f)).label, kBuilding);
  EXPECT_GT(tree->numSemanticNodes(), 0u);
  std::remove(path.c_str());

  eo::SaveMap bad;
  bad.request.path = "/nonexistent_dir/x.ot";
  ASSERT_TRUE(ros::service::call(kNode + "/save_map", bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("/nonexistent_dir/x.ot"), std::string::npos)
      << bad.response.message;
}

TEST_F(MappingNodeTest, LoadMapRestoresASavedMapAndRefusesBadFiles) {
  insert(lidarCloud(scene()));
  const std::string path =
      "/tmp/evidential_octomap_rostest_load_" + std::to_string(getpid()) + ".ot";
  eo::SaveMap save;
  save.request.path = path;
  ASSERT_TRUE(ros::service::call(kNode + "/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  callReset();
  ASSERT_EQ(query({gp(5.05, 0.0, 0.75)}).labels[0], -1);

  eo::LoadMap load;
  load.request.path = path;
  ASSERT_TRUE(ros::service::call(kNode + "/load_map", load));
  EXPECT_TRUE(load.response.success) << load.response.message;
  EXPECT_EQ(query({gp(5.05, 0.0, 0.75)}).labels[0], kBuilding);

  // A file that is not a map: refused with its name, the loaded map stays.
  const std::string junk = path + ".junk";
  { std::ofstream(junk) << "not an octree"; }
  eo::LoadMap bad;
  bad.request.path = junk;
  ASSERT_TRUE(ros::service::call(kNode + "/load_map", bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find(junk), std::string::npos) << bad.response.message;
  EXPECT_EQ(query({gp(5.05, 0.0, 0.75)}).labels[0], kBuilding);
  std::remove(path.c_str());
  std::remove(junk.c_str());
}

// The node maps at the resolution of the map it holds: a map loaded through ~load_map keeps its
// resolution through ~reset (the node must not fall back to ~resolution).
TEST_F(MappingNodeTest, ResetAfterLoadMapKeepsTheLoadedMapsResolution) {
  const std::string path =
      "/tmp/evidential_octomap_rostest_fine_" + std::to_string(getpid()) + ".ot";
  const std::string saved = path + ".after_reset.ot";
  {
    eo::EvidentialOcTree fine(0.1, kC);  // the node's ~resolution is 0.2
    fine.updateNode(octomap::point3d(1.f, 1.f, 1.f), true);
    eo::saveMap(fine, path);
  }
  eo::LoadMap load;
  load.request.path = path;
  ASSERT_TRUE(ros::service::call(kNode + "/load_map", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  callReset();
  eo::SaveMap save;
  save.request.path = saved;
  ASSERT_TRUE(ros::service::call(kNode + "/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(saved));
  ASSERT_NE(read, nullptr);
  EXPECT_DOUBLE_EQ(read->getResolution(), 0.1);
  EXPECT_EQ(read->size(), 0u);  // reset emptied it
  // Back to the node's ~resolution for the tests that follow (one node serves them all).
  {
    eo::EvidentialOcTree usual(0.2, kC);
    usual.updateNode(octomap::point3d(1.f, 1.f, 1.f), true);
    eo::saveMap(usual, path);
  }
  ASSERT_TRUE(ros::service::call(kNode + "/load_map", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  callReset();
  std::remove(path.c_str());
  std::remove(saved.c_str());
}

TEST_F(MappingNodeTest, EvidentialMapMessageHoldsTheSerialisedTree) {
  eo::EvidentialMapConstPtr map;
  ros::Subscriber sub = nh_.subscribe<eo::EvidentialMap>(
      "evidential_map", 1, [&](const eo::EvidentialMapConstPtr& m) { map = m; });
  ASSERT_TRUE(waitFor([&] { return sub.getNumPublishers() > 0; }));
  const ros::Time sent = ros::Time::now();
  insert(lidarCloud(scene()));
  // The latched map of the reset in SetUp may arrive first: wait for the one after the scan.
  ASSERT_TRUE(waitFor([&] { return map && map->header.stamp >= sent; }));
  EXPECT_EQ(map->num_classes, kC);
  EXPECT_EQ(map->fusion_rule, "dempster");
  std::stringstream s(std::string(map->data.begin(), map->data.end()));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(s));
  auto* tree = dynamic_cast<eo::EvidentialOcTree*>(read.get());
  ASSERT_NE(tree, nullptr);
  EXPECT_EQ(tree->query(octomap::point3d(5.05f, 0.f, 0.75f)).label, kBuilding);
}

TEST_F(MappingNodeTest, ResetEmptiesTheMap) {
  insert(lidarCloud(scene()));
  ASSERT_EQ(query({gp(5.05, 0.0, 0.75)}).labels[0], kBuilding);
  semantic_.reset();
  callReset();
  ASSERT_TRUE(waitFor([&] { return bool(semantic_); }));
  size_t cubes = 0;
  for (const auto& m : semantic_->markers) cubes += m.points.size();
  EXPECT_EQ(cubes, 0u);
  const auto r = query({gp(5.05, 0.0, 0.75), gp(2.5, 0.0, -1.5)});
  EXPECT_EQ(r.labels[0], -1);
  EXPECT_FLOAT_EQ(r.occupancy[0], -1.f);
  EXPECT_FLOAT_EQ(r.occupancy[1], -1.f);
}

TEST_F(MappingNodeTest, ClearBbxClearsOnlyInside) {
  insert(lidarCloud(scene()));
  eo::BoundingBoxQuery srv;  // octomap_server's request (octomap_msgs/BoundingBoxQuery's MD5)
  srv.request.min = gp(4.0, 0.5, -0.5);
  srv.request.max = gp(6.0, 3.0, 2.0);
  ASSERT_TRUE(ros::service::call(kNode + "/clear_bbx", srv));
  const auto r = query({gp(5.05, 1.0, 0.75), gp(5.05, 1.5, 0.3), gp(5.05, -1.0, 0.75),
                        gp(5.05, 0.3, 0.75), gp(2.5, 0.0, -1.5)});
  for (int i = 0; i < 2; ++i) {  // inside: free, no semantics
    EXPECT_EQ(r.labels[i], -1);
    EXPECT_GE(r.occupancy[i], 0.f);
    EXPECT_LT(r.occupancy[i], 0.5f);
  }
  EXPECT_EQ(r.labels[2], kBuilding);  // outside: kept
  EXPECT_EQ(r.labels[3], kBuilding);  // just outside the box edge (y < 0.5)
  EXPECT_EQ(r.labels[4], kRoad);
}

// Sets one double through dynamic_reconfigure's ~set_parameters.
bool setDouble(const std::string& name, double value) {
  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::DoubleParameter p;
  p.name = name;
  p.value = value;
  srv.request.config.doubles.push_back(p);
  return ros::service::call(kNode + "/set_parameters", srv);
}

TEST_F(MappingNodeTest, MaxRangeChangesAtRunTimeAndSurvivesReset) {
  // The wall is 4 m from the sensor, the road patch 1.9-2.8 m: a 3 m range keeps only the road.
  ASSERT_TRUE(setDouble("sensor_model_max_range", 3.0));
  callReset();
  insert(lidarCloud(scene()));
  auto r = query({gp(5.05, 0.0, 0.75), gp(2.5, 0.0, -1.5)});
  EXPECT_EQ(r.labels[0], -1);     // beyond range: no semantic evidence
  EXPECT_EQ(r.labels[1], kRoad);  // within range
  ASSERT_TRUE(setDouble("sensor_model_max_range", -1.0));
  callReset();
  insert(lidarCloud(scene()));
  r = query({gp(5.05, 0.0, 0.75)});
  EXPECT_EQ(r.labels[0], kBuilding);
}

// --- robustness ----------------------------------------------------------------------------

class RobustnessTest : public MappingNodeTest {
 protected:
  // A good map, then `bad` (whose points lie where the map is unknown): node alive, map
  // unchanged, and the node's log names the problem.
  void expectRejected(const sensor_msgs::PointCloud2& bad, const std::string& log_text,
                      int repeats = 1) {
    insert(lidarCloud(scene()));
    const auto before = snapshot();
    // ROS 1 may drop the first messages of a fresh connection (the cloud, or the log line on a
    // /rosout subscription still connecting): send the bad cloud again until the node says it.
    bool said = false;
    for (int attempt = 0; attempt < 10 && !said; ++attempt) {
      for (int i = 0; i < repeats; ++i) {
        auto msg = bad;
        msg.header.stamp = ros::Time::now();
        cloud_pub_.publish(msg);
        ros::WallDuration(0.05).sleep();
      }
      said = waitFor([&] { return logSays(log_text); }, 6.0);
    }
    EXPECT_TRUE(said) << "no log line with: " << log_text;
    const auto after = snapshot();  // the node answers: it is alive
    EXPECT_EQ(before, after) << "the bad cloud changed the map";
    EXPECT_EQ(query({gp(9.05, 0.0, 0.75)}).occupancy[0], -1.f);
  }
  // Bad clouds put a wall at map x = 9 where the good scene has nothing.
  std::vector<Point> farWall() { return scene(8.05f, 15); }
};

TEST_F(RobustnessTest, MissingEvidenceFieldIsRejected) {
  auto msg = lidarCloud(farWall());
  msg.fields[3].name = "intensity";
  expectRejected(msg, "no semantic field");
}

TEST_F(RobustnessTest, WrongEvidenceCountIsRejected) {
  expectRejected(lidarCloud(farWall(), "lidar", kC - 1), "has count 19, expected C = 20");
}

TEST_F(RobustnessTest, NanEvidenceIsRejected) {
  auto msg = lidarCloud(farWall());
  setEvidence(&msg, 7, 3, std::nanf(""));
  expectRejected(msg, "point 7: evidence of class 3 is nan");
}

TEST_F(RobustnessTest, InfiniteEvidenceIsRejected) {
  auto msg = lidarCloud(farWall());
  setEvidence(&msg, 8, 2, INFINITY);
  expectRejected(msg, "point 8: evidence of class 2 is inf");
}

TEST_F(RobustnessTest, NegativeEvidenceIsRejected) {
  auto msg = lidarCloud(farWall());
  setEvidence(&msg, 9, 1, -2.f);
  expectRejected(msg, "point 9: evidence of class 1 is -2");
}

TEST_F(RobustnessTest, TruncatedDataIsRejected) {
  auto msg = lidarCloud(farWall());
  msg.data.resize(msg.data.size() / 2);
  expectRejected(msg, "truncated data");
}

TEST_F(RobustnessTest, ZeroPointsIsRejected) {
  expectRejected(lidarCloud({}), "cloud has zero points");
}

TEST_F(RobustnessTest, MissingTfDropsTheCloud) {
  // No transform map <- nowhere ever arrives: the MessageFilter drops the oldest cloud once
  // its queue is full, and the node says so.
  expectRejected(lidarCloud(farWall(), "nowhere"), "no transform nowhere -> map", 8);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_mapping_node");
  ros::NodeHandle nh, pnh("~");
  pnh.param("server", kNode, kNode);
  pnh.param("log_node", kLogNode, kNode);
  return RUN_ALL_TESTS();
}
