// NodeAllocator, the store of the tree's nodes: distinct aligned cells, cells freed on any thread
// come back, empty chunks go back to the system, and a map built, cleared or reloaded over and
// over holds no more chunks than the first time (the node of a long-running process).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "node_allocator.h"
#include "synthetic_scene.h"

namespace evidential_octomap {
namespace {

constexpr size_t kCellsPerChunk = NodeAllocator::kChunkBytes / NodeAllocator::kCellBytes;

// The counters once this thread's cache is back in the store.
NodeAllocator::Counters settled() {
  NodeAllocator::flushThreadCache();
  return NodeAllocator::counters();
}

TEST(NodeAllocator, CellsAreDistinctAlignedAndKeepTheirContent) {
  const auto before = settled();
  const size_t n = 3 * kCellsPerChunk;  // several chunks
  std::vector<uint64_t*> cells(n);
  for (size_t i = 0; i < n; ++i) {
    cells[i] = static_cast<uint64_t*>(NodeAllocator::allocate());
    ASSERT_EQ(reinterpret_cast<uintptr_t>(cells[i]) % 16, 0u);
    cells[i][0] = i;
    cells[i][1] = ~uint64_t(i);
  }
  std::set<uint64_t*> distinct(cells.begin(), cells.end());
  EXPECT_EQ(distinct.size(), n);
  // No two cells overlap: sorted addresses are at least a cell apart.
  std::vector<uintptr_t> sorted;
  for (uint64_t* c : cells) sorted.push_back(reinterpret_cast<uintptr_t>(c));
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 1; i < n; ++i) ASSERT_GE(sorted[i] - sorted[i - 1], NodeAllocator::kCellBytes);
  for (size_t i = 0; i < n; ++i) {
    ASSERT_EQ(cells[i][0], i);
    ASSERT_EQ(cells[i][1], ~uint64_t(i));
  }
  const auto during = settled();
  EXPECT_EQ(during.cells_out, before.cells_out + n);
  // 16 B per cell, whole chunks: at most one chunk of slack, plus the header cells.
  EXPECT_LE(during.chunks, before.chunks + n / kCellsPerChunk + 2);
  for (uint64_t* c : cells) NodeAllocator::deallocate(c);
  const auto after = settled();
  EXPECT_EQ(after.cells_out, before.cells_out);
  EXPECT_LE(after.chunks, before.chunks + 1);  // the empty chunks were unmapped but one
}

TEST(NodeAllocator, FreedCellsAreReusedBeforeNewChunks) {
  std::vector<void*> cells;
  for (int i = 0; i < 1000; ++i) cells.push_back(NodeAllocator::allocate());
  const auto full = settled();
  std::mt19937 rng(3);
  for (int round = 0; round < 50; ++round) {
    std::shuffle(cells.begin(), cells.end(), rng);
    for (int i = 0; i < 500; ++i) NodeAllocator::deallocate(cells[i]);
    for (int i = 0; i < 500; ++i) cells[i] = NodeAllocator::allocate();
  }
  EXPECT_EQ(settled().chunks, full.chunks);
  EXPECT_EQ(std::set<void*>(cells.begin(), cells.end()).size(), cells.size());
  for (void* c : cells) NodeAllocator::deallocate(c);
}

TEST(NodeAllocator, ThreadsAllocateAndFreeEachOthersCells) {
  const auto before = settled();
  constexpr int kThreads = 4;
  constexpr size_t kPerThread = 100000;
  std::vector<std::vector<uint64_t*>> made(kThreads);
  {
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&made, t] {
        std::mt19937 rng(t);
        auto& mine = made[t];
        for (size_t i = 0; i < kPerThread; ++i) {
          auto* c = static_cast<uint64_t*>(NodeAllocator::allocate());
          c[0] = uint64_t(t) << 32 | i;
          mine.push_back(c);
          if (rng() % 3 == 0) {  // free a random earlier cell of this thread
            const size_t j = rng() % mine.size();
            NodeAllocator::deallocate(mine[j]);
            mine[j] = mine.back();
            mine.pop_back();
          }
        }
      });
    }
    for (auto& th : threads) th.join();
  }
  std::set<uint64_t*> all;
  for (const auto& v : made) all.insert(v.begin(), v.end());
  size_t total = 0;
  for (const auto& v : made) total += v.size();
  EXPECT_EQ(all.size(), total);  // no cell handed out twice
  EXPECT_EQ(settled().cells_out,
            before.cells_out + total);  // exited threads gave their caches back
  // Each thread frees another thread's cells.
  {
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&made, t] {
        for (uint64_t* c : made[(t + 1) % kThreads]) NodeAllocator::deallocate(c);
      });
    }
    for (auto& th : threads) th.join();
  }
  const auto after = settled();
  EXPECT_EQ(after.cells_out, before.cells_out);
  EXPECT_LE(after.chunks, before.chunks + 1);
}

// A map of the synthetic scene, with `threads` for the tree update, plus a block of leaves in a
// checkerboard of hits and misses (nothing prunes) spanning several chunks.
std::unique_ptr<EvidentialOcTree> mapScene(int threads) {
  test::SyntheticScene scene;
  SemanticConfig config;
  config.threads = threads;
  auto tree = std::make_unique<EvidentialOcTree>(0.2, scene.num_classes, config);
  for (unsigned seed = 1; seed <= 2; ++seed) {
    const test::SyntheticScan scan = scene.defaultScan(seed);
    tree->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  }
  const octomap::OcTreeKey corner = tree->coordToKey(octomap::point3d(-40.f, -40.f, -20.f));
  for (int x = 0; x < 96; ++x)
    for (int y = 0; y < 96; ++y)
      for (int z = 0; z < 40; ++z) {
        const octomap::OcTreeKey key(static_cast<octomap::key_type>(corner[0] + x),
                                     static_cast<octomap::key_type>(corner[1] + y),
                                     static_cast<octomap::key_type>(corner[2] + z));
        tree->updateNode(key, (x + y + z) % 2 == 0);
      }
  return tree;
}

TEST(NodeAllocator, TreeNodesComeFromTheAllocatorAndGoBackOnClearAndDestruction) {
  const auto before = settled();
  auto tree = mapScene(1);
  const auto mapped = settled();
  ASSERT_GT(tree->size(), 4 * kCellsPerChunk);
  EXPECT_EQ(mapped.cells_out - before.cells_out, tree->size());  // every node, nothing else
  tree->clear();
  EXPECT_EQ(settled().cells_out, before.cells_out);
  auto again = mapScene(1);
  tree.reset();
  again.reset();
  EXPECT_EQ(settled().cells_out, before.cells_out);
}

// The ROS node's clear / load_map services, many times: chunks do not accumulate.
TEST(NodeAllocator, BuildClearAndReloadCyclesDoNotGrow) {
  const auto before = settled();
  std::stringstream file;
  {
    auto tree = mapScene(2);
    ASSERT_TRUE(tree->write(file));
  }
  const std::string bytes = file.str();
  size_t first_peak = 0;
  for (int cycle = 0; cycle < 4; ++cycle) {
    auto tree = mapScene(2);  // parallel update: worker threads' caches hold a few cells
    tree->clear();
    std::istringstream in(bytes);
    std::unique_ptr<octomap::AbstractOcTree> loaded(octomap::AbstractOcTree::read(in));
    ASSERT_NE(dynamic_cast<EvidentialOcTree*>(loaded.get()), nullptr);
    const size_t peak = settled().chunks;
    if (cycle == 0) first_peak = peak;
    ASSERT_GE(peak, before.chunks + 4);  // the map spans several chunks
    EXPECT_LE(peak, first_peak) << "cycle " << cycle;
    loaded.reset();
    tree.reset();
    const auto after = settled();
    // What is still out sits in the (at most two) OpenMP workers' caches: 2 x 128 cells.
    EXPECT_LE(after.cells_out, before.cells_out + 256) << "cycle " << cycle;
    EXPECT_LE(after.chunks, before.chunks + 3) << "cycle " << cycle;
  }
}

}  // namespace
}  // namespace evidential_octomap
