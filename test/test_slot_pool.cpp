// SlotPool, the store of semantic payloads: slots stay put while the pool grows, released
// slots are reused, and the per-thread Local hands slots out and back without losing any.
#include <gtest/gtest.h>

#include <set>
#include <vector>

#include "slot_pool.h"

namespace evidential_octomap {
namespace {

TEST(SlotPool, SlotsKeepTheirAddressAndContentWhileThePoolGrows) {
  SlotPool pool(3);
  SlotPool::Local local(&pool, 1);
  std::vector<std::pair<uint32_t, float*>> slots;
  for (int i = 0; i < 5 * int(SlotPool::kBlockSlots); ++i) {
    const uint32_t index = local.allocate();
    float* p = pool.slot(index);
    p[0] = float(i);
    p[2] = -float(i);
    slots.emplace_back(index, p);
  }
  local.flush();
  EXPECT_EQ(pool.inUse(), slots.size());
  std::set<uint32_t> distinct;
  for (size_t i = 0; i < slots.size(); ++i) {
    distinct.insert(slots[i].first);
    ASSERT_EQ(pool.slot(slots[i].first), slots[i].second);
    ASSERT_EQ(slots[i].second[0], float(i));
    ASSERT_EQ(slots[i].second[2], -float(i));
  }
  EXPECT_EQ(distinct.size(), slots.size());
  // No doubling: the pool holds whole blocks, at most one of them partly used.
  EXPECT_LE(pool.bytes(), (slots.size() + SlotPool::kBlockSlots) * 3 * sizeof(float) + 4096);
}

TEST(SlotPool, ReleasedSlotsAreReusedBeforeTheBlocksGrow) {
  SlotPool pool(2);
  std::vector<uint32_t> first;
  {
    SlotPool::Local local(&pool, 64);
    for (int i = 0; i < 1000; ++i) first.push_back(local.allocate());
    for (int i = 0; i < 500; ++i) local.release(first[i]);
  }  // the destructor gives back what was not used
  EXPECT_EQ(pool.inUse(), 500u);
  const size_t bytes = pool.bytes();
  {
    SlotPool::Local other(&pool, 64);
    std::set<uint32_t> again;
    for (int i = 0; i < 500; ++i) again.insert(other.allocate());
    EXPECT_EQ(again.size(), 500u);
  }
  EXPECT_EQ(pool.inUse(), 1000u);
  EXPECT_LE(pool.bytes(), bytes + 4096);  // no new block (the free list may have grown)
  pool.reset(4);
  EXPECT_EQ(pool.inUse(), 0u);
  EXPECT_EQ(pool.width(), 4);
}

}  // namespace
}  // namespace evidential_octomap
