#include "payload_store.h"

#include <algorithm>
#include <cstring>

namespace evidential_octomap {
namespace {

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

uint32_t maskWord(const float* slot, int w) {
  uint32_t word;
  std::memcpy(&word, slot + w, sizeof(word));
  return word;
}

}  // namespace

void PayloadStore::reset(int num_classes, float prior) {
  num_classes_ = num_classes;
  prior_ = prior;
  mask_words_ = (num_classes + 31) / 32;
  pools_.clear();
  for (int cap = 1; cap < num_classes; cap *= 2) {
    pools_.push_back(std::make_unique<SlotPool>(mask_words_ + cap));
  }
  pools_.push_back(std::make_unique<SlotPool>(num_classes));  // dense
}

int PayloadStore::capacity(int size_class) const {
  return isDense(size_class) ? num_classes_ : 1 << size_class;
}

int PayloadStore::sizeClassFor(int count) const {
  int size_class = 0;
  while (!isDense(size_class) && capacity(size_class) < count) ++size_class;
  return size_class;
}

void PayloadStore::decode(uint32_t ref, float* out) const {
  const int size_class = sizeClassOf(ref);
  const float* slot = pools_[size_class]->slot(indexOf(ref));
  if (isDense(size_class)) {
    std::memcpy(out, slot, sizeof(float) * num_classes_);
    return;
  }
  std::fill_n(out, num_classes_, prior_);
  const float* value = slot + mask_words_;
  for (int w = 0; w < mask_words_; ++w) {
    for (uint32_t mask = maskWord(slot, w); mask != 0; mask &= mask - 1) {
      std::memcpy(out + 32 * w + __builtin_ctz(mask), value++, sizeof(float));
    }
  }
}

double PayloadStore::sum(uint32_t ref) const {
  const int size_class = sizeClassOf(ref);
  const float* slot = pools_[size_class]->slot(indexOf(ref));
  double total = 0.0;
  if (isDense(size_class)) {
    for (int c = 0; c < num_classes_; ++c) total += slot[c];
    return total;
  }
  const float* value = slot + mask_words_;
  if (sameBits(prior_, 0.0f)) {  // adding +0.0 to a sum that starts at +0.0 changes no bit
    int count = 0;
    for (int w = 0; w < mask_words_; ++w) count += __builtin_popcount(maskWord(slot, w));
    for (int i = 0; i < count; ++i) total += value[i];
    return total;
  }
  for (int w = 0; w < mask_words_; ++w) {
    uint32_t mask = maskWord(slot, w);
    for (int c = 32 * w; c < std::min(num_classes_, 32 * w + 32); ++c, mask >>= 1) {
      total += (mask & 1u) ? *value++ : prior_;
    }
  }
  return total;
}

bool PayloadStore::holdsAny(uint32_t ref, const uint32_t* classes) const {
  const int size_class = sizeClassOf(ref);
  const float* slot = pools_[size_class]->slot(indexOf(ref));
  if (isDense(size_class)) {
    for (int c = 0; c < num_classes_; ++c)
      if ((classes[c / 32] >> (c % 32) & 1u) && !sameBits(slot[c], prior_)) return true;
    return false;
  }
  for (int w = 0; w < mask_words_; ++w)
    if (maskWord(slot, w) & classes[w]) return true;
  return false;
}

int PayloadStore::encode(const float* values, float* sparse) const {
  float* value = sparse + mask_words_;
  for (int w = 0; w < mask_words_; ++w) {
    uint32_t mask = 0;
    // Without a branch per class (which of them a voxel holds is the data's): every value is
    // written, and the next one goes over it unless it is kept.
    for (int c = 32 * w; c < std::min(num_classes_, 32 * w + 32); ++c) {
      const uint32_t keep = !sameBits(values[c], prior_);
      std::memcpy(value, values + c, sizeof(float));
      value += keep;
      mask |= keep << (c % 32);
    }
    std::memcpy(sparse + w, &mask, sizeof(mask));
  }
  return int(value - sparse) - mask_words_;
}

size_t PayloadStore::inUse() const {
  size_t total = 0;
  for (const auto& pool : pools_) total += pool->inUse();
  return total;
}

size_t PayloadStore::bytes() const {
  size_t total = 0;
  for (const auto& pool : pools_) total += pool->bytes();
  return total;
}

// --- Local -----------------------------------------------------------------------------------

SlotPool::Local& PayloadStore::Local::pool(int size_class) {
  auto& local = locals_[size_class];
  if (!local)
    local = std::make_unique<SlotPool::Local>(store_->pools_[size_class].get(), batch_);
  return *local;
}

uint32_t PayloadStore::Local::allocate(int size_class) {
  return makeRef(size_class, pool(size_class).allocate());
}

uint32_t PayloadStore::Local::store(uint32_t ref, const float* values) {
  const PayloadStore& s = *store_;
  if (ref != kNone && s.isDense(sizeClassOf(ref))) {  // holds any values: no encoding
    std::memcpy(s.pools_[sizeClassOf(ref)]->slot(indexOf(ref)), values,
                sizeof(float) * s.num_classes_);
    return ref;
  }
  float sparse[kMaxMaskWords + 256];
  const int count = s.encode(values, sparse);
  // A payload only grows: it keeps a slot larger than it needs (compactPayloads refits).
  if (ref == kNone || s.capacity(sizeClassOf(ref)) < count) {
    if (ref != kNone) release(ref);
    ref = allocate(s.sizeClassFor(count));
  }
  float* slot = s.pools_[sizeClassOf(ref)]->slot(indexOf(ref));
  if (s.isDense(sizeClassOf(ref))) {
    std::memcpy(slot, values, sizeof(float) * s.num_classes_);
  } else {
    std::memcpy(slot, sparse, sizeof(float) * (s.mask_words_ + count));
  }
  return ref;
}

uint32_t PayloadStore::Local::copy(uint32_t ref) {
  const int size_class = sizeClassOf(ref);
  const uint32_t to = allocate(size_class);
  SlotPool& pool = *store_->pools_[size_class];
  std::memcpy(pool.slot(indexOf(to)), pool.slot(indexOf(ref)), sizeof(float) * pool.width());
  return to;
}

void PayloadStore::Local::release(uint32_t ref) { pool(sizeClassOf(ref)).release(indexOf(ref)); }

void PayloadStore::Local::flush() {
  for (auto& local : locals_) {
    if (local) local->flush();
  }
}

}  // namespace evidential_octomap
