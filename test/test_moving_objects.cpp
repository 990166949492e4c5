// Moving objects leave no ghosts (SemanticConfig::clearing_observations, off by default, and
// movable_clearing_observations for the classes a class table marks movable, on), with
// the library defaults and the live profile (config/mapping_live.yaml) otherwise: a SYNTHETIC
// street, a 0.6 x 0.6 x 1.8 m person walking 7.5 m across the view of a 32-beam LiDAR 8 m away
// (50 scans), then the empty street; fast free space still clearing what a mover left; the
// discount's rules on single voxels.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/settings.h"

namespace evidential_octomap {
namespace {

constexpr int kClasses = 4;
constexpr int kGround = 0, kPerson = 1, kWall = 2;
constexpr float kEvidence = 10.0f;  // one-hot evidence of the true class (derived)
constexpr int kClearings = 3;       // clearing_observations of the maps that discount

// The street: ground z = 0.1, a wall at x = 20.1 m (both mid-voxel), the person's box (when present).
struct Street {
  bool person = false;
  octomap::point3d person_min, person_max;

  // First hit of the ray (o, d) and its class; false when the ray meets nothing within 30 m.
  bool cast(const octomap::point3d& o, const octomap::point3d& d, octomap::point3d* hit,
            int* label) const {
    float best = std::numeric_limits<float>::infinity();
    if (d.z() < 0.0f) best = (0.1f - o.z()) / d.z(), *label = kGround;  // mid-voxel
    if (d.x() > 0.0f && (20.1f - o.x()) / d.x() < best) best = (20.1f - o.x()) / d.x(), *label = kWall;
    if (person) {
      const float t = boxDistance(o, d);
      if (t < best) best = t, *label = kPerson;
    }
    if (!(best < 30.0f)) return false;
    *hit = o + d * best;
    return true;
  }
  float boxDistance(const octomap::point3d& o, const octomap::point3d& d) const {
    float t_near = 0.0f, t_far = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (std::fabs(d(a)) < 1e-9f) continue;
      float t0 = (person_min(a) - o(a)) / d(a), t1 = (person_max(a) - o(a)) / d(a);
      if (t0 > t1) std::swap(t0, t1);
      t_near = std::max(t_near, t0), t_far = std::min(t_far, t1);
    }
    return t_near <= t_far ? t_near : std::numeric_limits<float>::infinity();
  }
};

// A 32-beam LiDAR (elevation uniform +-22.5 deg) at 1.8 m, azimuth -35 .. 35 deg in 0.35 deg.
const octomap::point3d kSensor(0.0f, 0.0f, 1.8f);

void scanOf(const Street& street, const octomap::point3d& sensor, octomap::Pointcloud* points,
            std::vector<float>* evidence) {
  for (int beam = 0; beam < 32; ++beam) {
    const double elevation = (-22.5 + 45.0 * beam / 31.0) * M_PI / 180.0;
    for (double azimuth = -35.0; azimuth <= 35.0; azimuth += 0.35) {
      const double a = azimuth * M_PI / 180.0;
      const octomap::point3d d(std::cos(elevation) * std::cos(a),
                               std::cos(elevation) * std::sin(a), std::sin(elevation));
      octomap::point3d hit;
      int label = 0;
      if (!street.cast(sensor, d, &hit, &label)) continue;
      points->push_back(hit);
      for (int c = 0; c < kClasses; ++c) evidence->push_back(c == label ? kEvidence : 0.0f);
    }
  }
}

void insertScan(const Street& street, EvidentialOcTree* tree,
                const octomap::point3d& sensor = kSensor) {
  octomap::Pointcloud points;
  std::vector<float> evidence;
  scanOf(street, sensor, &points, &evidence);
  tree->insertSemanticScan(points, evidence, sensor);
}

// The swept voxels, each with its log-odds after the last scan in which the person covered it.
struct PersonRun {
  std::map<std::tuple<int, int, int>, float> swept;
  std::set<std::tuple<int, int, int>> road;  // the ground voxels under its path
};

// The freed swept volume: swept voxels that are free and that rays have cleared since the person
// was last in them (log-odds lower than then); a ghost answers `person` to a query (the support
// answer of semantic_occupied_only included). A voxel freed only before the person came and never crossed
// by a ray since (between two beams' cones) keeps what the kernel gave it: nothing observes it.
struct GhostShare {
  double ghosts = 1.0;  // share of the freed voxels that answer `person`
  size_t freed = 0;
};

GhostShare ghostShare(const EvidentialOcTree& tree, const PersonRun& run) {
  size_t freed = 0, ghosts = 0;
  for (const auto& [k, then] : run.swept) {
    const auto& [x, y, z] = k;
    const octomap::OcTreeKey key(x, y, z);
    const EvidentialOcTreeNode* node = tree.search(key);
    if (!node || tree.isNodeOccupied(node) || !(node->getLogOdds() < then)) continue;
    ++freed;
    if (tree.answer(key).label == kPerson) ++ghosts;  // what a query answers
  }
  return {freed ? double(ghosts) / double(freed) : 1.0, freed};
}

// The person walks y = -3.75 .. 3.75 m at x = 8 m in 50 scans (1.5 m/s at 10 scans/s); its
// box's voxels are the swept set.
void walkPerson(EvidentialOcTree* tree, PersonRun* run) {
  Street street;
  street.person = true;
  for (int scan = 0; scan < 50; ++scan) {
    const float y = -3.75f + 7.5f * scan / 49.0f;
    street.person_min = octomap::point3d(7.7f, y - 0.3f, 0.1f);
    street.person_max = octomap::point3d(8.3f, y + 0.3f, 1.9f);
    insertScan(street, tree);
    for (float x = 7.7f; x < 8.4f; x += 0.2f)
      for (float yy = y - 0.3f; yy < y + 0.4f; yy += 0.2f) {
        const octomap::OcTreeKey k = tree->coordToKey(octomap::point3d(x, yy, 0.1f));
        run->road.insert({k[0], k[1], k[2]});
      }
    for (float x = 7.9f; x < 8.2f; x += 0.2f)
      for (float yy = y - 0.2f; yy < y + 0.3f; yy += 0.2f)
        for (float z = 0.3f; z < 1.8f; z += 0.2f) {  // above the ground's voxel layer
          const octomap::OcTreeKey k = tree->coordToKey(octomap::point3d(x, yy, z));
          const EvidentialOcTreeNode* node = tree->search(k);
          run->swept[{k[0], k[1], k[2]}] = node ? node->getLogOdds() : 0.0f;
        }
  }
}

// Ground voxels under the path that are occupied, and the share of them that answer `ground`.
double roadShare(const EvidentialOcTree& tree, const PersonRun& run, size_t* count) {
  size_t road = 0, kept = 0;
  for (const auto& [x, y, z] : run.road) {
    const octomap::OcTreeKey k(x, y, z);
    const EvidentialOcTreeNode* node = tree.search(k);
    if (!node || !tree.isNodeOccupied(node)) continue;
    ++road;
    kept += tree.answer(k).label == kGround;
  }
  *count = road;
  return road ? double(kept) / double(road) : 0.0;
}

// One thread, the ground a ground class (as a class table marks it); `movable`: the person a
// movable class too.
EvidentialOcTree streetMap(SemanticConfig config, bool movable = false) {
  config.threads = 1;
  EvidentialOcTree tree(0.2, kClasses, config);
  tree.setGroundClasses({true, false, false, false});
  if (movable) tree.setMovableClasses({false, true, false, false});
  return tree;
}
EvidentialOcTree streetMap(int clearing_observations) {
  SemanticConfig config;
  config.clearing_observations = clearing_observations;
  return streetMap(config);
}

// config/mapping_live.yaml over the defaults, as the launch files load it.
SemanticConfig liveProfile() {
  SemanticConfig config;
  std::ifstream in(EVIDENTIAL_OCTOMAP_SOURCE_DIR "/config/mapping_live.yaml");
  EXPECT_TRUE(in.good());
  for (std::string line; std::getline(in, line);) {
    line = line.substr(0, line.find('#'));
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string name = line.substr(0, colon), value = line.substr(colon + 1);
    name.erase(name.find_last_not_of(' ') + 1);
    value.erase(0, value.find_first_not_of(' '));
    value.erase(value.find_last_not_of(" \r") + 1);
    if (name == "settings_profile") continue;
    const Setting* setting = findSetting(name);
    EXPECT_TRUE(setting && setting->parse(value, &config)) << line;
  }
  EXPECT_TRUE(config.semantic_occupied_only);
  return config;
}

void walkThenEmpty(EvidentialOcTree* tree, PersonRun* run, int empty_scans) {
  walkPerson(tree, run);
  Street empty;
  for (int scan = 0; scan < empty_scans; ++scan) insertScan(empty, tree);
}

// The person walks past, then 10 scans of the empty street: most of its volume is freed (by ray
// casting or fast free space), at most 2 % of that still answers `person`, and the road under
// its path still answers road.
void expectFewGhostsAndTheRoad(EvidentialOcTree* tree) {
  PersonRun run;
  walkThenEmpty(tree, &run, 10);
  const GhostShare after10 = ghostShare(*tree, run);
  EXPECT_GT(after10.freed, run.swept.size() / 2);
  EXPECT_LE(after10.ghosts, 0.02);
  size_t road = 0;
  EXPECT_GE(roadShare(*tree, run, &road), 0.95);
  EXPECT_GT(road, 20u);
}

// Library defaults with the mode on (it is off by default: docs/long_missions.md).
TEST(MovingObjects, DefaultsLeaveFewGhostsTenScansAfterThePersonLeft) {
  EvidentialOcTree tree = streetMap(kClearings);
  expectFewGhostsAndTheRoad(&tree);
}

TEST(MovingObjects, LiveProfileLeavesFewGhostsAndKeepsTheRoad) {
  SemanticConfig live = liveProfile();
  live.clearing_observations = kClearings;
  EvidentialOcTree tree = streetMap(live);
  expectFewGhostsAndTheRoad(&tree);
}

// The defaults clear the classes a class table marks movable after one clearing.
TEST(MovingObjects, DefaultsLeaveFewGhostsOfAMovableClass) {
  EvidentialOcTree tree = streetMap(SemanticConfig(), true);
  expectFewGhostsAndTheRoad(&tree);
}

TEST(MovingObjects, LiveProfileLeavesFewGhostsOfAMovableClass) {
  EvidentialOcTree tree = streetMap(liveProfile(), true);
  expectFewGhostsAndTheRoad(&tree);
}

TEST(MovingObjects, WithoutDiscountTheGhostStays) {
  EvidentialOcTree tree = streetMap(0);
  PersonRun run;
  walkThenEmpty(&tree, &run, 10);
  EXPECT_GT(ghostShare(tree, run).ghosts, 0.3);  // the failure the setting exists for
}

TEST(MovingObjects, StaticSurfacesKeepTheirClass) {
  // The ground is hit and, at grazing angles, passed through; the wall is hit every scan.
  EvidentialOcTree with = streetMap(kClearings), without = streetMap(0);
  PersonRun run_with, run_without;
  walkPerson(&with, &run_with);
  walkPerson(&without, &run_without);
  size_t occupied = 0, same = 0;
  for (auto it = without.begin_leafs(); it != without.end_leafs(); ++it) {
    const octomap::OcTreeKey k = it.getKey();
    if (!without.isNodeOccupied(*it) || run_without.swept.count({k[0], k[1], k[2]})) continue;
    const int label = without.opinion(&*it).label;
    if (label != kGround && label != kWall) continue;
    const EvidentialOcTreeNode* node = with.search(it.getKey());
    ++occupied;
    if (node && with.isNodeOccupied(node) && with.opinion(node).label == label) ++same;
  }
  ASSERT_GT(occupied, 1000u);
  EXPECT_GE(double(same) / double(occupied), 0.99) << same << " of " << occupied;
}

// The longest piece of a ray from `origin` to one of `ends` inside the voxel `key`.
double longestChord(const EvidentialOcTree& tree, const octomap::OcTreeKey& key,
                    const octomap::point3d& origin, const octomap::Pointcloud& ends) {
  const octomap::point3d centre = tree.keyToCoord(key);
  const double half = tree.getResolution() / 2.0;
  double longest = 0.0;
  for (const octomap::point3d& end : ends) {
    const octomap::point3d d = end - origin;
    double t_in = 0.0, t_out = 1.0;  // of origin + t d
    for (int a = 0; a < 3; ++a) {
      const double lo = centre(a) - half - origin(a), hi = centre(a) + half - origin(a);
      if (d(a) == 0.0f) {
        if (lo > 0.0 || hi < 0.0) t_out = -1.0;
        continue;
      }
      const double t0 = std::min(lo / d(a), hi / d(a)), t1 = std::max(lo / d(a), hi / d(a));
      t_in = std::max(t_in, t0);
      t_out = std::min(t_out, t1);
    }
    if (t_out > t_in) longest = std::max(longest, (t_out - t_in) * d.norm());
  }
  return longest;
}

// Fast free space takes a shortcut through space this scan already cleared: in an empty map some
// voxels that only shortcut rays cross stay unobserved. Where such a voxel holds what a mover
// left (occupied, with class evidence) the ray must still clear it. The sensor sits off every
// voxel face here: from a face, rays pass exactly through voxel edges, where either neighbour
// is the ray's (the exact DDA and the walk back from the end may choose differently).
TEST(MovingObjects, FastFreeSpaceClearsWhatAMoverLeftBehindClearedSpace) {
  const octomap::point3d sensor(0.013f, -0.007f, 1.833f);
  SemanticConfig fast_config;
  fast_config.fast_free_space = true;
  EvidentialOcTree exact = streetMap(SemanticConfig()), fast = streetMap(fast_config);
  Street empty;
  insertScan(empty, &exact, sensor);
  insertScan(empty, &fast, sensor);
  std::vector<octomap::OcTreeKey> skipped;  // free in the exact map, unknown in the fast one
  for (auto it = exact.begin_leafs(); it != exact.end_leafs(); ++it) {
    if (!exact.isNodeOccupied(*it) && !fast.search(it.getKey())) skipped.push_back(it.getKey());
  }
  ASSERT_GT(skipped.size(), 100u);  // the shortcut saves work on this scan

  EvidentialOcTree left = streetMap(fast_config);
  std::vector<VoxelUpdate> hits;
  std::vector<double> rows;
  for (const octomap::OcTreeKey& k : skipped) {
    hits.push_back(VoxelUpdate{k, +1, uint32_t(hits.size())});
    for (int c = 0; c < kClasses; ++c) rows.push_back(c == kPerson ? 2.0 : 0.0);
  }
  detail::TreeEditing::applyUpdates(left, hits, rows, false);
  const float before = left.search(skipped[0])->getLogOdds();
  insertScan(empty, &left, sensor);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  scanOf(empty, sensor, &points, &evidence);
  size_t cleared = 0;
  for (const octomap::OcTreeKey& k : skipped) {
    if (left.search(k)->getLogOdds() < before) {
      ++cleared;
      continue;
    }
    EXPECT_LT(longestChord(left, k, sensor, points), 1e-3 * left.getResolution())
        << "voxel " << k[0] << ", " << k[1] << ", " << k[2] << " crossed but not cleared";
  }
  std::printf("cleared %zu of %zu\n", cleared, skipped.size());
}

// A leaf with evidence for class 2 through applyUpdates: free (a miss, as kernel evidence in
// free space), or occupied (a hit).
EvidentialOcTreeNode* leafWithEvidence(EvidentialOcTree* tree, const octomap::OcTreeKey& key,
                                       float amount, int8_t occupancy = -1) {
  std::vector<double> row(kClasses, 0.0);
  row[2] = amount;
  detail::TreeEditing::applyUpdates(*tree, {VoxelUpdate{key, occupancy, 0}}, row, false);
  return detail::TreeEditing::leafForUpdate(*tree, key, false);
}

void clear(EvidentialOcTree* tree, const octomap::OcTreeKey& key, int times) {
  for (int i = 0; i < times; ++i) detail::TreeEditing::applyUpdates(*tree, {VoxelUpdate{key, -1}}, {}, false);
}

TEST(ClearingDiscount, LargestPayloadIsGoneAfterTheStatedClearingsNotBefore) {
  EvidentialOcTree tree = streetMap(kClearings);
  const octomap::OcTreeKey key(32768, 32768, 32768);
  leafWithEvidence(&tree, key, float(kMaxStoredLogEvidence));
  clear(&tree, key, kClearings - 1);
  EXPECT_EQ(tree.query(key).label, 2);
  clear(&tree, key, 1);
  EXPECT_EQ(tree.query(key).label, -1);
  EXPECT_EQ(tree.numSemanticNodes(), 0u);
}

TEST(ClearingDiscount, KeepsTheClassSharesAndRaisesUncertainty) {
  EvidentialOcTree tree = streetMap(kClearings);
  const octomap::OcTreeKey key(32768, 32768, 32768);
  std::vector<double> row{1.0, 0.5, 2.0, 0.0};
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, -1, 0}}, row, false);
  const std::vector<float> before = tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false));
  const float u_before = tree.query(key).uncertainty;
  clear(&tree, key, 1);
  const std::vector<float> after = tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false));
  const double keep = SemanticConfig::clearingKeep(kClearings);
  for (int c = 0; c < kClasses; ++c) EXPECT_NEAR(after[c], before[c] * keep, 1e-6);
  EXPECT_EQ(tree.query(key).label, 2);
  EXPECT_GT(tree.query(key).uncertainty, u_before);
}

// Contextual discounting: a class that this scan's kernel row still gives the cleared voxel (a
// static surface beside it, seen again) keeps what the voxel held; the others are discounted as
// when no row comes, and the row is added after.
TEST(ClearingDiscount, ClassesTheScanStillShowsKeepTheirEvidence) {
  EvidentialOcTree tree = streetMap(kClearings);
  const octomap::OcTreeKey key(32768, 32768, 32768);
  const std::vector<double> held{1.0, 0.5, 2.0, 0.3};
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, -1, 0}}, held, false);
  const std::vector<double> row{0.0, 0.0, 0.4, 0.05};  // shows class 2; class 3 too little
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, -1, 0}}, row, false);
  const std::vector<float> after = tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false));
  const double keep = SemanticConfig::clearingKeep(kClearings);
  ASSERT_LT(keep, 0.5);
  EXPECT_NEAR(after[0], 1.0 * keep, 1e-6);
  EXPECT_NEAR(after[1], 0.5 * keep, 1e-6);
  EXPECT_NEAR(after[2], 2.0 + 0.4, 1e-6);
  EXPECT_NEAR(after[3], 0.3 * keep + 0.05, 1e-6);
}

// A surface that rays sometimes graze: a miss that leaves the voxel occupied is no clearing of
// its class.
TEST(ClearingDiscount, OccupiedVoxelKeepsItsEvidenceWhenARayGrazesIt) {
  EvidentialOcTree tree = streetMap(kClearings);
  const octomap::OcTreeKey key(32768, 32768, 32768);
  leafWithEvidence(&tree, key, 1.0f, +1);
  for (int i = 0; i < 3; ++i) leafWithEvidence(&tree, key, 0.0f, +1);  // hit four times
  const std::vector<float> before = tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false));
  clear(&tree, key, 2);
  EXPECT_TRUE(tree.isNodeOccupied(tree.search(key)));
  EXPECT_EQ(tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false)), before);
}

TEST(ClearingDiscount, HitsBetweenClearingsKeepTheClass) {
  EvidentialOcTree tree = streetMap(kClearings);
  const octomap::OcTreeKey key(32768, 32768, 32768);
  leafWithEvidence(&tree, key, 1.0f);
  std::vector<double> row(kClasses, 0.0);
  row[2] = 1.0;
  for (int round = 0; round < 50; ++round) {
    clear(&tree, key, 3);  // passed through three times, then hit again with its evidence
    detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, +1, 0}}, row, false);
  }
  EXPECT_EQ(tree.query(key).label, 2);
}

// A map that keeps its evidence on the surface answers a voxel without evidence from the
// surface around it; a voxel whose own evidence the clearings removed was seen empty and answers
// no class, not its neighbour's.
TEST(ClearingDiscount, SurfaceMapClearedVoxelAnswersNoClassNotItsNeighbours) {
  SemanticConfig config;
  config.semantic_occupied_only = true;
  config.clearing_observations = kClearings;
  EvidentialOcTree tree = streetMap(config);
  const octomap::OcTreeKey cleared(32768, 32768, 32768), person(32769, 32768, 32768),
      beside(32770, 32768, 32768);
  leafWithEvidence(&tree, cleared, 1.0f);
  std::vector<double> row(kClasses, 0.0);
  row[kPerson] = 1.0;
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{person, +1, 0}}, row, false);
  clear(&tree, beside, 1);  // known, free, never any evidence of its own
  EXPECT_EQ(tree.answer(beside).label, kPerson);  // the support answer
  clear(&tree, cleared, kClearings);
  EXPECT_EQ(tree.query(cleared).label, -1);
  EXPECT_EQ(tree.answer(cleared).label, -1);
}

// A movable class's evidence goes after movable_clearing_observations clearings (1 by default);
// a static class in the same voxel keeps what it had while clearing_observations is off.
TEST(ClearingDiscount, MovableClassGoesStaticClassStays) {
  EvidentialOcTree tree = streetMap(SemanticConfig());
  const octomap::OcTreeKey key(32768, 32768, 32768);
  std::vector<double> held(kClasses, 0.0);
  held[kPerson] = 3.0;
  held[kWall] = 0.5;
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, -1, 0}}, held, false);
  ASSERT_EQ(tree.query(key).label, kPerson);
  tree.setMovableClasses({false, true, false, false});
  clear(&tree, key, 1);
  const std::vector<float> after = tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false));
  EXPECT_LT(after[kPerson], float(SemanticConfig::kReleasedEvidence));
  EXPECT_NEAR(after[kWall], 0.5, 1e-6);
  EXPECT_EQ(tree.query(key).label, kWall);
}

// The mover's own points spread its class into the voxels it has just left: in a voxel seen
// empty that evidence neither protects what the voxel held nor is added, while a static class's
// is (contextual discounting as before).
TEST(ClearingDiscount, AVoxelSeenEmptyTakesNoEvidenceOfAMovableClass) {
  SemanticConfig config;
  config.clearing_observations = kClearings;
  EvidentialOcTree tree = streetMap(config);
  const octomap::OcTreeKey key(32768, 32768, 32768);
  std::vector<double> held(kClasses, 0.0);
  held[kPerson] = 3.0;
  held[kWall] = 0.5;
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, -1, 0}}, held, false);
  tree.setMovableClasses({false, true, false, false});
  std::vector<double> row(kClasses, 0.0);
  row[kPerson] = 2.0;  // the person beside the voxel shows its class strongly
  row[kWall] = 1.0;
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, -1, 0}}, row, false);
  const std::vector<float> after = tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false));
  EXPECT_LT(after[kPerson], float(SemanticConfig::kReleasedEvidence));
  EXPECT_NEAR(after[kWall], 0.5 + 1.0, 1e-6);
  EXPECT_EQ(tree.query(key).label, kWall);
  // Hit, the voxel is a surface again and takes the person's evidence.
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, +1, 0}}, row, false);
  EXPECT_GT(tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false))[kPerson], 1.0f);
}

// Only the movable classes clear by default: a voxel that holds none of them keeps its static
// evidence bit for bit however often rays find it empty, even below the release threshold.
TEST(ClearingDiscount, AVoxelWithoutMovableEvidenceKeepsItsStaticEvidence) {
  EvidentialOcTree tree = streetMap(SemanticConfig());
  tree.setMovableClasses({false, true, false, false});
  const octomap::OcTreeKey key(32768, 32768, 32768);
  std::vector<double> held(kClasses, 0.0);
  held[kWall] = 0.5 * SemanticConfig::kReleasedEvidence;
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, -1, 0}}, held, false);
  const std::vector<float> before =
      tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false));
  ASSERT_GT(before[kWall], 0.0f);
  clear(&tree, key, 5);
  EXPECT_EQ(tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false)), before);
}

TEST(ClearingDiscount, WithoutMovableClassesTheDefaultsClearNothing) {
  EvidentialOcTree tree = streetMap(SemanticConfig());
  const octomap::OcTreeKey key(32768, 32768, 32768);
  std::vector<double> held(kClasses, 0.0);
  held[kPerson] = 3.0;
  detail::TreeEditing::applyUpdates(tree, {VoxelUpdate{key, -1, 0}}, held, false);
  clear(&tree, key, 5);
  EXPECT_EQ(tree.query(key).label, kPerson);
}

TEST(ClearingDiscount, TheFewerClearingsApply) {
  SemanticConfig config;
  config.clearing_observations = 3;
  config.movable_clearing_observations = 1;
  EXPECT_EQ(config.clearingsOf(true), 1);
  EXPECT_EQ(config.clearingsOf(false), 3);
  config.movable_clearing_observations = 5;
  EXPECT_EQ(config.clearingsOf(true), 3);
  config.movable_clearing_observations = 0;
  EXPECT_EQ(config.clearingsOf(true), 3);
  config.clearing_observations = 0;
  EXPECT_EQ(config.clearingsOf(true), 0);
  EXPECT_EQ(SemanticConfig::clearingKeep(0), 1.0);
}

TEST(ClearingDiscount, MovableFlagsMustCoverEveryClass) {
  EvidentialOcTree tree = streetMap(SemanticConfig());
  EXPECT_THROW(tree.setMovableClasses({true, false}), std::invalid_argument);
  EXPECT_NO_THROW(tree.setMovableClasses({}));
}

TEST(ClearingDiscount, OffLeavesPayloadsUntouched) {
  EvidentialOcTree tree = streetMap(0);
  const octomap::OcTreeKey key(32768, 32768, 32768);
  leafWithEvidence(&tree, key, 1.0f);
  const std::vector<float> before = tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false));
  clear(&tree, key, 100);
  EXPECT_EQ(tree.payload(detail::TreeEditing::leafForUpdate(tree, key, false)), before);
}

TEST(ClearingDiscount, RefusesCountsOutsideItsRange) {
  SemanticConfig config;
  config.clearing_observations = -1;
  EXPECT_NE(config.problem().find("clearing_observations"), std::string::npos);
  config.clearing_observations = SemanticConfig::kMaxClearingObservations + 1;
  EXPECT_NE(config.problem(), "");
  config.clearing_observations = 10;
  EXPECT_EQ(config.problem(), "");
  config.movable_clearing_observations = -1;
  EXPECT_NE(config.problem().find("movable_clearing_observations"), std::string::npos);
}

}  // namespace
}  // namespace evidential_octomap
