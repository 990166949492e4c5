// VoxelBricks, the per-scan voxel set of ray casting: every key comes back once, with its
// flags, in Morton order (the order the tree update needs), also after merging two sets.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "morton.h"
#include "voxel_bricks.h"

namespace evidential_octomap {
namespace {

using Entry = std::tuple<uint64_t, unsigned>;  // (Morton code, flags)

// The expected content, computed independently: a std::map keyed by an explicit bit
// interleaving (z, y, x from most to least significant).
uint64_t interleave(const octomap::OcTreeKey& k) {
  uint64_t code = 0;
  for (int bit = 15; bit >= 0; --bit) {
    code = (code << 3) | (uint64_t((k[2] >> bit) & 1) << 2) | (uint64_t((k[1] >> bit) & 1) << 1) |
           uint64_t((k[0] >> bit) & 1);
  }
  return code;
}

std::vector<Entry> contents(const VoxelBricks& bricks) {
  std::vector<Entry> out;
  bricks.forEachSorted([&](const octomap::OcTreeKey& key, uint64_t code, unsigned flags) {
    EXPECT_EQ(code, interleave(key));
    out.emplace_back(code, flags);
  });
  return out;
}

std::vector<octomap::OcTreeKey> randomKeys(unsigned seed, int count) {
  std::mt19937 rng(seed);
  // Clustered around the map centre like a scan, plus keys at the extremes of the key range.
  std::uniform_int_distribution<int> near(32768 - 300, 32768 + 300), any(0, 65535);
  std::vector<octomap::OcTreeKey> keys;
  for (int i = 0; i < count; ++i) {
    const bool far = i % 50 == 0;
    keys.emplace_back(far ? any(rng) : near(rng), far ? any(rng) : near(rng),
                      far ? any(rng) : near(rng) / 16 + 30000);
  }
  keys.emplace_back(0, 0, 0);
  keys.emplace_back(65535, 65535, 65535);
  return keys;
}

TEST(VoxelBricks, ReturnsEveryKeyOnceWithItsFlagsInMortonOrder) {
  VoxelBricks bricks;
  std::map<uint64_t, unsigned> expected;
  std::mt19937 rng(4);
  std::uniform_int_distribution<int> flag(0, VoxelBricks::kFlags - 1);
  for (const auto& key : randomKeys(1, 200000)) {
    const int f = flag(rng);
    const bool was = (expected[interleave(key)] >> f) & 1u;
    EXPECT_EQ(bricks.testAndSet(key, f), was);
    EXPECT_TRUE(bricks.test(key, f));
    expected[interleave(key)] |= 1u << f;
  }
  bricks.sortBricks();
  const std::vector<Entry> got = contents(bricks);
  ASSERT_EQ(got.size(), expected.size());
  size_t i = 0;
  for (const auto& [code, flags] : expected) {
    ASSERT_EQ(got[i], Entry(code, flags)) << "entry " << i;
    ++i;
  }
  EXPECT_EQ(mortonCode(octomap::OcTreeKey(1, 2, 3)), interleave(octomap::OcTreeKey(1, 2, 3)));
  EXPECT_EQ(keyFromMorton(mortonCode(octomap::OcTreeKey(40000, 7, 65535))),
            octomap::OcTreeKey(40000, 7, 65535));
}

TEST(VoxelBricks, MergeIsTheUnionOfFlags) {
  VoxelBricks a, b, both;
  const auto keys = randomKeys(2, 50000);
  for (size_t i = 0; i < keys.size(); ++i) {
    const int f = static_cast<int>(i % VoxelBricks::kFlags);
    (i % 3 == 0 ? a : b).testAndSet(keys[i], f);
    both.testAndSet(keys[i], f);
  }
  a.merge(b);
  a.sortBricks();
  both.sortBricks();
  EXPECT_EQ(contents(a), contents(both));
}

TEST(VoxelBricks, ClearEmptiesAndKeepsWorking) {
  VoxelBricks bricks;
  for (const auto& key : randomKeys(3, 10000)) bricks.testAndSet(key, 0);
  bricks.clear();
  EXPECT_TRUE(bricks.empty());
  bricks.sortBricks();
  EXPECT_TRUE(contents(bricks).empty());
  const octomap::OcTreeKey key(32768, 32768, 32768);
  EXPECT_FALSE(bricks.test(key, 1));
  EXPECT_FALSE(bricks.testAndSet(key, 1));
  EXPECT_TRUE(bricks.testAndSet(key, 1));
  bricks.sortBricks();
  EXPECT_EQ(contents(bricks), std::vector<Entry>{Entry(interleave(key), 2u)});
}

}  // namespace
}  // namespace evidential_octomap
