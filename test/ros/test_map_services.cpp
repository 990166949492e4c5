// The ~query and ~clear_bbx handlers (map_services.h) without a roscore, and the node's
// parameter checks that need no parameter server: non-finite query points are unknown (they
// used to reach OctoMap's search(point), undefined behaviour), refused boxes change nothing, the
// dynamic_reconfigure sliders stay inside the core's ranges.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

#include "map_services.h"
#include "node_test_utils.h"
#include "ros_params.h"

namespace evidential_octomap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
using node_test::gp;

EvidentialOcTree wallMap() {
  EvidentialOcTree tree(0.2, 3);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (float y = -1.f; y <= 1.f; y += 0.1f) {
    for (float z = -0.5f; z <= 0.5f; z += 0.1f) {
      points.push_back(3.05f, y, z);
      evidence.insert(evidence.end(), {0.f, 20.f, 0.f});
    }
  }
  tree.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.f));
  return tree;
}

std::string bytesOf(const EvidentialOcTree& tree) {
  std::ostringstream out;
  tree.write(out);
  return out.str();
}

TEST(QueryService, NonFinitePointsAreUnknown) {
  const EvidentialOcTree tree = wallMap();
  QueryMap::Request req;
  req.points = {gp(3.05, 0.0, 0.05), gp(kNaN, 0, 0),    gp(0, kNaN, 0),   gp(kInf, 0, 0),
                gp(-kInf, 0, 0),     gp(1e30, 1e30, 0), gp(3.05, 0, kNaN)};
  QueryMap::Response res;
  answerQuery(tree, req, &res);
  ASSERT_EQ(res.labels.size(), req.points.size());
  ASSERT_EQ(res.beliefs.size(), req.points.size() * 3);
  EXPECT_EQ(res.labels[0], 1);
  EXPECT_GT(res.occupancy[0], 0.5f);
  for (size_t i = 1; i < req.points.size(); ++i) {
    EXPECT_EQ(res.labels[i], -1) << i;
    EXPECT_FLOAT_EQ(res.occupancy[i], -1.f) << i;
    EXPECT_FLOAT_EQ(res.uncertainties[i], 1.f) << i;
  }
}

TEST(ClearBbxService, RefusedBoxesSayWhyAndChangeNothing) {
  EvidentialOcTree tree = wallMap();
  const std::string before = bytesOf(tree);
  for (const auto& [min, max] : {std::make_pair(gp(2, -1, -1), gp(kNaN, kNaN, kNaN)),
                                 std::make_pair(gp(2, -1, -1), gp(kNaN, 1000, 1000)),
                                 std::make_pair(gp(4, -1, -1), gp(2, 1, 1))}) {
    ClearBbx::Request req;
    req.min = min;
    req.max = max;
    ClearBbx::Response res;
    clearBoxRequest(&tree, req, &res);
    EXPECT_FALSE(res.success);
    EXPECT_NE(res.message.find("refused"), std::string::npos) << res.message;
    EXPECT_EQ(res.voxels_cleared, 0u);
  }
  EXPECT_TRUE(bytesOf(tree) == before) << "a refused box changed the map";
  ClearBbx::Request req;
  req.min = gp(2, -2, -2);
  req.max = gp(4, 2, 2);
  ClearBbx::Response res;
  clearBoxRequest(&tree, req, &res);
  EXPECT_TRUE(res.success) << res.message;
  EXPECT_GT(res.voxels_cleared, 0u);
}

// Every value a dynamic_reconfigure client can set for the sensor model is inside the core's
// ranges (hit 1 or clamp 0/1 made maps that could not be loaded).
TEST(ReconfigureLimits, SensorModelSlidersStayInsideTheCoreRanges) {
  MappingConfig lo, hi;
  reconfigureLimits(&lo, &hi);
  // Every corner of the slider box is a valid model (clamp min below clamp max is the one rule
  // between sliders, checked when a value is set).
  for (double hit : {lo.sensor_model_hit, hi.sensor_model_hit})
    for (double miss : {lo.sensor_model_miss, hi.sensor_model_miss})
      for (double clamp_min : {lo.sensor_model_min, hi.sensor_model_min})
        for (double clamp_max : {lo.sensor_model_max + 0.1, hi.sensor_model_max}) {
          const SensorModel model{hit, miss, clamp_min, clamp_max, 0.5};
          EXPECT_EQ(model.problem(), "")
              << hit << " " << miss << " " << clamp_min << " " << clamp_max;
        }
  // The generated defaults (Mapping.cfg) agree with the core too.
  const MappingConfig cfg_lo = MappingConfig::__getMin__(), cfg_hi = MappingConfig::__getMax__();
  EXPECT_GE(cfg_lo.sensor_model_hit, SensorModel::kMinHit);
  EXPECT_LE(cfg_hi.sensor_model_hit, SensorModel::kMaxHit);
  EXPECT_GE(cfg_lo.sensor_model_miss, SensorModel::kMinMiss);
  EXPECT_LE(cfg_hi.sensor_model_miss, SensorModel::kMaxMiss);
  EXPECT_GE(cfg_lo.sensor_model_min, SensorModel::kMinClampMin);
  EXPECT_LE(cfg_hi.sensor_model_min, SensorModel::kMaxClampMin);
  EXPECT_GE(cfg_lo.sensor_model_max, SensorModel::kMinClampMax);
  EXPECT_LE(cfg_hi.sensor_model_max, SensorModel::kMaxClampMax);
}

TEST(ReconfigureLimits, UnaffordableKernelAndBadSensorModelsAreRefused) {
  SemanticConfig semantic;
  const SensorModel good{0.7, 0.4, 0.12, 0.97, 0.5};
  EXPECT_EQ(reconfigureProblem(semantic, good, 0.2), "");
  semantic.length_scale = 5.0;  // inside Mapping.cfg's range ...
  semantic.beta = 10.0;
  EXPECT_NE(reconfigureProblem(semantic, good, 0.2).find("leaves"), std::string::npos);
  EXPECT_NE(reconfigureProblem(SemanticConfig(), {1.0, 0.4, 0.12, 0.97, 0.5}, 0.2), "");
  EXPECT_NE(reconfigureProblem(SemanticConfig(), {0.7, 0.4, 0.5, 0.5, 0.5}, 0.2), "");
}

}  // namespace
}  // namespace evidential_octomap

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
