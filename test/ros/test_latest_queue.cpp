// LatestQueue: the node's bounded queue of the newest clouds. Full → the oldest item is pushed
// out and handed back (so it can be counted); pop is FIFO; close wakes a waiting consumer.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "latest_queue.h"

using evidential_octomap::LatestQueue;

TEST(LatestQueue, KeepsTheNewestAndHandsBackTheDropped) {
  LatestQueue<int> queue(2);
  EXPECT_FALSE(queue.push(1));
  EXPECT_FALSE(queue.push(2));
  const std::optional<int> dropped = queue.push(3);
  ASSERT_TRUE(dropped);
  EXPECT_EQ(*dropped, 1);
  EXPECT_EQ(*queue.push(4), 2);
  EXPECT_EQ(queue.size(), 2u);
  EXPECT_EQ(*queue.pop(), 3);
  EXPECT_EQ(*queue.pop(), 4);
  EXPECT_EQ(queue.size(), 0u);
}

TEST(LatestQueue, CapacityOneAlwaysHoldsTheLatest) {
  LatestQueue<int> queue(1);
  for (int i = 0; i < 10; ++i) {
    const auto dropped = queue.push(i);
    EXPECT_EQ(bool(dropped), i > 0);
    if (dropped) EXPECT_EQ(*dropped, i - 1);
  }
  EXPECT_EQ(*queue.pop(), 9);
}

TEST(LatestQueue, ZeroCapacityIsRefused) {
  EXPECT_THROW(LatestQueue<int>(0), std::invalid_argument);
}

TEST(LatestQueue, CloseWakesAWaitingConsumer) {
  LatestQueue<int> queue(3);
  std::atomic<bool> returned{false};
  std::optional<int> got = 7;
  std::thread consumer([&] {
    got = queue.pop();  // blocks: the queue is empty
    returned = true;
  });
  queue.close();
  consumer.join();
  EXPECT_TRUE(returned);
  EXPECT_FALSE(got);
}

// waitFor: false when nothing came within the timeout; true at once when an item waits or the
// queue is closed (pop would not wait), and it takes nothing out.
TEST(LatestQueue, WaitForSaysWhetherPopWouldWait) {
  LatestQueue<int> queue(2);
  EXPECT_FALSE(queue.waitFor(std::chrono::milliseconds(20)));
  queue.push(5);
  EXPECT_TRUE(queue.waitFor(std::chrono::milliseconds(0)));
  EXPECT_EQ(queue.size(), 1u);
  EXPECT_EQ(*queue.pop(), 5);
  std::thread producer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    queue.push(6);
  });
  EXPECT_TRUE(queue.waitFor(std::chrono::seconds(30)));  // woken by the push
  producer.join();
  EXPECT_EQ(*queue.pop(), 6);
  queue.close();
  EXPECT_TRUE(queue.waitFor(std::chrono::milliseconds(0)));
}

// Every pushed item is either popped or handed back as dropped, exactly once, with one producer
// and one consumer running at the same time.
TEST(LatestQueue, EveryItemIsPoppedOrDroppedExactlyOnce) {
  constexpr int kItems = 20000;
  LatestQueue<int> queue(4);
  std::vector<int> seen(kItems, 0);
  std::thread consumer([&] {
    while (auto item = queue.pop()) {
      ++seen[*item];
      if (*item == kItems - 1) break;  // the last item is never dropped: nothing comes after it
    }
  });
  std::vector<int> dropped;
  for (int i = 0; i < kItems; ++i)
    if (auto d = queue.push(i)) dropped.push_back(*d);
  consumer.join();
  for (int d : dropped) ++seen[d];
  for (int i = 0; i < kItems; ++i) EXPECT_EQ(seen[i], 1) << "item " << i;
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
