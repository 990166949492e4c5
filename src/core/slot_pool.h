// Slots of a fixed number of floats (one size class of the payload store, payload_store.h), in
// fixed blocks of kBlockSlots slots, so the pool grows without the doubling slack and the 2x copy peak of one std::vector, and a slot
// never moves (threads may read slots while others allocate). Released slots are reused first.
// Private to the core.
#pragma once

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

namespace evidential_octomap {

class SlotPool {
 public:
  static constexpr uint32_t kBlockSlots = 2048;
  static constexpr uint32_t kMaxBlocks = 1u << 17;  // 2^28 slots
  static constexpr uint32_t kNone = 0xFFFFFFFFu;

  explicit SlotPool(int width) : width_(width) {}
  ~SlotPool() { reset(width_); }
  SlotPool(const SlotPool&) = delete;
  SlotPool& operator=(const SlotPool&) = delete;

  int width() const { return width_; }
  // Drops every slot; `width` floats per slot from now on.
  void reset(int width);

  float* slot(uint32_t index) {
    return blocks_[index / kBlockSlots] + size_t(index % kBlockSlots) * width_;
  }
  const float* slot(uint32_t index) const {
    return blocks_[index / kBlockSlots] + size_t(index % kBlockSlots) * width_;
  }

  // Slots handed out and not released.
  size_t inUse() const { return in_use_; }
  // Bytes held: blocks, free list and directory.
  size_t bytes() const;

  // Hands out slots to one thread of a parallel pass, taking them from the pool in batches, and
  // keeps the slots that thread releases for its own reuse. Give back what is left with flush()
  // (also done by the destructor). For serial use a batch of 1 keeps the pool exact.
  class Local {
   public:
    Local(SlotPool* pool, uint32_t batch) : pool_(pool), batch_(batch) {}
    Local(const Local&) = delete;
    Local& operator=(const Local&) = delete;
    ~Local() { flush(); }
    uint32_t allocate();  // uninitialised contents
    void release(uint32_t index);
    void flush();

   private:
    SlotPool* pool_;
    uint32_t batch_;
    std::vector<uint32_t> spare_;
    long long in_use_delta_ = 0;
  };

 private:
  void take(uint32_t count, std::vector<uint32_t>* into);               // locked
  void giveBack(std::vector<uint32_t>* slots, long long in_use_delta);  // locked

  int width_;
  // kMaxBlocks block pointers, allocated once (calloc: pages cost memory only once touched) and
  // never moved, so threads may read slots while another thread adds a block.
  float** blocks_ = nullptr;
  uint32_t num_blocks_ = 0;
  uint32_t fresh_ = 0;              // slots [fresh_, num_blocks_ * kBlockSlots) never used
  std::vector<uint32_t> released_;  // reused first
  size_t in_use_ = 0;
  std::mutex mutex_;
};

}  // namespace evidential_octomap
