#include "slot_pool.h"

#include <cstdlib>
#include <new>
#include <stdexcept>

namespace evidential_octomap {

void SlotPool::reset(int width) {
  for (uint32_t b = 0; b < num_blocks_; ++b) delete[] blocks_[b];
  std::free(blocks_);
  blocks_ = nullptr;
  num_blocks_ = 0;
  fresh_ = 0;
  released_.clear();
  released_.shrink_to_fit();
  in_use_ = 0;
  width_ = width;
}

size_t SlotPool::bytes() const {
  return size_t(num_blocks_) * kBlockSlots * width_ * sizeof(float) +
         released_.capacity() * sizeof(uint32_t) +
         size_t(num_blocks_) * sizeof(float*);  // directory pages in use
}

void SlotPool::take(uint32_t count, std::vector<uint32_t>* into) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (; count > 0 && !released_.empty(); --count) {
    into->push_back(released_.back());
    released_.pop_back();
  }
  for (; count > 0; --count) {
    if (fresh_ == size_t(num_blocks_) * kBlockSlots) {
      if (num_blocks_ == kMaxBlocks) throw std::length_error("semantic payload pool is full");
      if (!blocks_) {
        blocks_ = static_cast<float**>(std::calloc(kMaxBlocks, sizeof(float*)));
        if (!blocks_) throw std::bad_alloc();
      }
      blocks_[num_blocks_] = new float[size_t(kBlockSlots) * width_];
      ++num_blocks_;
    }
    into->push_back(fresh_++);
  }
}

void SlotPool::giveBack(std::vector<uint32_t>* slots, long long in_use_delta) {
  std::lock_guard<std::mutex> lock(mutex_);
  released_.insert(released_.end(), slots->begin(), slots->end());
  slots->clear();
  in_use_ = static_cast<size_t>(static_cast<long long>(in_use_) + in_use_delta);
}

uint32_t SlotPool::Local::allocate() {
  if (spare_.empty()) pool_->take(batch_, &spare_);
  const uint32_t index = spare_.back();
  spare_.pop_back();
  ++in_use_delta_;
  return index;
}

void SlotPool::Local::release(uint32_t index) {
  spare_.push_back(index);
  --in_use_delta_;
}

void SlotPool::Local::flush() {
  if (spare_.empty() && in_use_delta_ == 0) return;
  pool_->giveBack(&spare_, in_use_delta_);
  in_use_delta_ = 0;
}

}  // namespace evidential_octomap
