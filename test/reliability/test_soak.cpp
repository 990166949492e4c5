// Long-run numerics: many small synthetic scans into one tree, with random evidence
// that includes zeros and huge values. Afterwards (and along the way) every voxel reads out
// finite, with |sum(b) + u - 1| <= 1e-5, and memory stays bounded.
//   test_soak [--scans N] [--points P] [--classes C] [gtest flags]
// ctest runs 300 scans; the full soak is `test_soak --scans 10000`
// (docs/experiments/reliability.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {
namespace {

int g_scans = 500;
int g_points = 200;
int g_classes = 8;

long rssKb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::atol(line.c_str() + 6);
  }
  return -1;
}

struct ReadoutCheck {
  size_t nodes = 0, semantic = 0, bad = 0;
  double worst_sum_error = 0.0;
  float max_payload = 0.0f;
  std::string first_problem;
};

// Every node's readout (inner nodes included) is finite and a valid opinion.
ReadoutCheck checkAll(const EvidentialOcTree& tree) {
  ReadoutCheck check;
  for (auto it = tree.begin_tree(), end = tree.end_tree(); it != end; ++it) {
    ++check.nodes;
    const std::vector<float> payload = tree.payload(&*it);
    if (payload.empty()) continue;
    ++check.semantic;
    for (int c = 0; c < tree.numClasses(); ++c) {
      check.max_payload = std::max(check.max_payload, payload[c]);
    }
    const VoxelOpinion o = tree.opinion(&*it);
    double sum = o.uncertainty;
    bool ok = std::isfinite(o.uncertainty) && o.uncertainty >= 0.0f && o.uncertainty <= 1.0f;
    for (float b : o.belief) {
      ok = ok && std::isfinite(b) && b >= 0.0f && b <= 1.0f;
      sum += b;
    }
    const double error = std::fabs(sum - 1.0);
    if (std::isfinite(error)) check.worst_sum_error = std::max(check.worst_sum_error, error);
    if (!ok || !(error <= 1e-5)) {
      if (check.bad++ == 0) {
        char text[256];
        std::snprintf(text, sizeof(text), "node at depth %u: u = %g, sum(b) + u - 1 = %g, "
                      "payload[0] = %g", it.getDepth(), o.uncertainty, sum - 1.0, payload[0]);
        check.first_problem = text;
      }
    }
  }
  return check;
}

// One small scan: points in a 10 x 10 x 3 m box seen from a sensor inside it, evidence with
// zeros, ordinary values, confident points and huge (1e30) values.
void makeScan(std::mt19937& rng, int n, int num_classes, octomap::Pointcloud* points,
              std::vector<float>* evidence, octomap::point3d* origin) {
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  *origin = octomap::point3d(10.f * u01(rng), 10.f * u01(rng), 1.0f + u01(rng));
  points->clear();
  evidence->clear();
  for (int i = 0; i < n; ++i) {
    points->push_back(10.f * u01(rng), 10.f * u01(rng), 3.f * u01(rng));
    const float kind = u01(rng);
    const int cls = static_cast<int>(u01(rng) * num_classes) % num_classes;
    for (int c = 0; c < num_classes; ++c) {
      float e;
      if (kind < 0.10f) e = 0.0f;                                    // no evidence at all
      else if (kind < 0.15f) e = (c == cls) ? 1e30f : 0.0f;          // huge, one class
      else if (kind < 0.17f) e = 1e30f * u01(rng);                   // huge, every class
      else if (kind < 0.20f) e = (c == cls) ? 1e6f : 1e-6f * u01(rng);  // very confident
      else e = (c == cls) ? 50.f * u01(rng) : 2.f * u01(rng);        // ordinary
      evidence->push_back(e);
    }
  }
}

TEST(Soak, ManySmallScansStayFiniteNormalisedAndBounded) {
  EvidentialOcTree tree(0.2, g_classes);
  std::mt19937 rng(8);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  octomap::point3d origin;
  const auto start = std::chrono::steady_clock::now();
  const int check_every = std::max(1, g_scans / 10);
  size_t memory_at_60 = 0, nodes_at_60 = 0;
  long rss_at_60 = 0, rss_start = rssKb();
  for (int scan = 1; scan <= g_scans; ++scan) {
    makeScan(rng, g_points, g_classes, &points, &evidence, &origin);
    ASSERT_NO_THROW(tree.insertSemanticScan(points, evidence, origin)) << "scan " << scan;
    if (scan % check_every == 0 || scan == g_scans) {
      const ReadoutCheck check = checkAll(tree);
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::printf("[soak] scan %6d: %zu nodes, %zu semantic, memoryUsage %.2f MB, RSS %.1f MB, "
                  "max L %.1f, worst |sum(b)+u-1| %.2e, bad %zu, %.1f s\n",
                  scan, check.nodes, check.semantic, tree.memoryUsage() / 1e6, rssKb() / 1e3,
                  check.max_payload, check.worst_sum_error, check.bad, seconds);
      std::fflush(stdout);
      ASSERT_EQ(check.bad, 0u) << "after scan " << scan << ": " << check.first_problem;
      EXPECT_LE(check.worst_sum_error, 1e-5);
    }
    if (scan == (g_scans * 6) / 10) {
      memory_at_60 = tree.memoryUsage();
      nodes_at_60 = tree.size();
      rss_at_60 = rssKb();
    }
  }
  // The box is 10 x 10 x 3 m and the kernel support is below 1 m: at 0.2 m that is at most
  // about 60 x 60 x 25 leaves. Memory must have stopped growing with the scans.
  const size_t leaf_bound = 62 * 62 * 27;
  EXPECT_LE(tree.getNumLeafNodes(), leaf_bound);
  if (g_scans >= 300) {  // (too few scans to see a plateau below that)
    EXPECT_LE(tree.memoryUsage(), memory_at_60 * 5 / 4 + 65536)
        << "memoryUsage still grows: " << memory_at_60 << " B at 60 % of the scans, "
        << tree.memoryUsage() << " B at the end";
    EXPECT_LE(tree.size(), nodes_at_60 * 5 / 4 + 1000);
    EXPECT_LE(rssKb(), rss_at_60 * 5 / 4 + 32 * 1024) << "RSS still grows";
  }
  std::printf("[soak] done: %d scans x %d points, C = %d: %zu nodes (%zu leaves), %zu semantic; "
              "memoryUsage %.2f MB (%.2f MB at 60 %%); RSS %.1f MB (start %.1f, at 60 %% %.1f)\n",
              g_scans, g_points, g_classes, tree.size(), tree.getNumLeafNodes(),
              tree.numSemanticNodes(), tree.memoryUsage() / 1e6, memory_at_60 / 1e6,
              rssKb() / 1e3, rss_start / 1e3, rss_at_60 / 1e3);
}

// Values at the top of the float range: finite, so accepted, and they must not turn into inf or
// NaN inside the integrator (e.g. when down-sampling averages two of them in one cell).
TEST(Soak, LargestFiniteEvidenceStaysFinite) {
  for (float huge : {1e30f, 1e38f, std::numeric_limits<float>::max()}) {
    EvidentialOcTree tree(0.2, 3);
    octomap::Pointcloud points;
    std::vector<float> evidence;
    for (int i = 0; i < 4; ++i) {  // four points in one down-sampling cell
      points.push_back(2.0f + 0.001f * i, 1.0f, 0.5f);
      evidence.insert(evidence.end(), {huge, huge, 0.0f});
    }
    points.push_back(2.5f, 1.0f, 0.5f);
    evidence.insert(evidence.end(), {huge, 0.0f, 0.0f});
    ASSERT_NO_THROW(tree.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.5f)));
    const ReadoutCheck check = checkAll(tree);
    EXPECT_GT(check.semantic, 0u);
    EXPECT_EQ(check.bad, 0u) << "evidence " << huge << ": " << check.first_problem;
  }
}

// inf, NaN and negative evidence are rejected with std::invalid_argument before the map changes.
TEST(Soak, NonFiniteOrNegativeEvidenceIsRejected) {
  EvidentialOcTree tree(0.2, 3);
  octomap::Pointcloud good;
  good.push_back(2.0f, 0.0f, 0.0f);
  tree.insertSemanticScan(good, {5.0f, 0.0f, 0.0f}, octomap::point3d(0.f, 0.f, 0.f));
  const size_t nodes = tree.size(), semantic = tree.numSemanticNodes();
  const VoxelOpinion before = tree.query(octomap::point3d(2.0f, 0.0f, 0.0f));
  for (float bad : {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                    std::numeric_limits<float>::quiet_NaN(), -1.0f, -1e-30f}) {
    octomap::Pointcloud points;
    points.push_back(2.0f, 0.0f, 0.0f);
    points.push_back(3.0f, 1.0f, 0.0f);
    EXPECT_THROW(tree.insertSemanticScan(points, {1.0f, 1.0f, 1.0f, 1.0f, bad, 1.0f},
                                         octomap::point3d(0.f, 0.f, 0.f)),
                 std::invalid_argument)
        << "evidence " << bad;
  }
  EXPECT_EQ(tree.size(), nodes);
  EXPECT_EQ(tree.numSemanticNodes(), semantic);
  const VoxelOpinion after = tree.query(octomap::point3d(2.0f, 0.0f, 0.0f));
  EXPECT_EQ(after.belief, before.belief);
  EXPECT_EQ(after.uncertainty, before.uncertainty);
}

// Points far outside the map (±1e30) are skipped and a non-finite origin is refused, without
// undefined behaviour: OctoMap's coordToKeyChecked casts coordinate / resolution to int, so the
// core must test the extent first (visible under UBSan with -fsanitize=float-cast-overflow,
// which clang's -fsanitize=undefined includes and GCC's does not).
TEST(Soak, PointsFarOutsideTheMapAreSkipped) {
  EvidentialOcTree tree(0.2, 2);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (float far : {1e30f, -1e30f, 1e10f, 7000.f}) {
    points.push_back(far, 0.f, 0.f);
    points.push_back(1.f, far, 0.f);
    points.push_back(1.f, 0.f, far);
  }
  points.push_back(2.f, 0.f, 0.f);  // one ordinary point
  evidence.assign(points.size() * 2, 1.0f);
  InsertStats stats;
  ASSERT_NO_THROW(stats = tree.insertSemanticScan(points, evidence, octomap::point3d(0, 0, 0)));
  EXPECT_EQ(stats.points_skipped, points.size() - 1);
  EXPECT_EQ(tree.query(octomap::point3d(1e30f, 0.f, 0.f)).label, -1);
  EXPECT_EQ(tree.query(octomap::point3d(std::nanf(""), 0.f, 0.f)).label, -1);
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    1e30f}) {
    octomap::Pointcloud one;
    one.push_back(2.f, 0.f, 0.f);
    EXPECT_THROW(tree.insertSemanticScan(one, {1.0f, 1.0f}, octomap::point3d(bad, 0.f, 0.f)),
                 std::invalid_argument)
        << "origin x = " << bad;
  }
}

}  // namespace
}  // namespace evidential_octomap

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);  // removes the gtest flags
  // scripts/sanitize.sh shortens the soak under sanitizers (EVIDENTIAL_SOAK_SCANS caps --scans).
  const char* cap = std::getenv("EVIDENTIAL_SOAK_SCANS");
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return std::atoi(argv[++i]);
    };
    if (arg == "--scans") evidential_octomap::g_scans = std::max(1, next());
    else if (arg == "--points") evidential_octomap::g_points = std::max(1, next());
    else if (arg == "--classes") evidential_octomap::g_classes = std::max(1, next());
    else {
      std::fprintf(stderr, "unknown argument %s (use --scans N --points P --classes C)\n",
                   arg.c_str());
      return 2;
    }
  }
  if (cap && std::atoi(cap) > 0) {
    evidential_octomap::g_scans = std::min(evidential_octomap::g_scans, std::atoi(cap));
  }
  return RUN_ALL_TESTS();
}
