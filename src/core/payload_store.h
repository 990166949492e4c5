// The semantic payloads of a tree, sparse: a slot holds only the classes whose value differs
// from the rule's prior (a class bitmask, then those values in class order), in size classes of
// 1, 2, 4, 8, ... values, one SlotPool each; the last size class holds all C values densely
// (no mask). A payload that outgrows its slot moves to a larger size class. A reference names
// the size class (top 4 bits) and the slot in its pool. Readers decode a payload into C floats,
// which are bit for bit what a dense slot would hold. Private to the core.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "slot_pool.h"

namespace evidential_octomap {

class PayloadStore {
 public:
  static constexpr uint32_t kNone = 0xFFFFFFFFu;
  static constexpr int kMaxSizeClasses = 9;  // 1, 2, 4, ..., 128 values, then dense (C <= 255)
  static constexpr int kMaxMaskWords = 8;    // 255 classes

  PayloadStore(int num_classes, float prior) { reset(num_classes, prior); }
  PayloadStore(const PayloadStore&) = delete;
  PayloadStore& operator=(const PayloadStore&) = delete;

  // Drops every payload; C values per payload and `prior` for the classes not stored from now on.
  void reset(int num_classes, float prior);
  // The prior of an empty store may change (a map's rule changes only while it holds no payload).
  void setPrior(float prior) { prior_ = prior; }
  int numClasses() const { return num_classes_; }
  float prior() const { return prior_; }

  // The C values of `ref` into `out`.
  void decode(uint32_t ref, float* out) const;
  // Sum of the C values in class order (what std::accumulate over the decoded values gives).
  double sum(uint32_t ref) const;
  // Whether `ref` holds a value other than the prior for a class of `classes` (bit c % 32 of
  // word c / 32): a look at the class mask, without decoding.
  bool holdsAny(uint32_t ref, const uint32_t* classes) const;

  // Payloads stored.
  size_t inUse() const;
  // Bytes held by the pools (slots, free lists, directories).
  size_t bytes() const;

  // One thread's allocations (SlotPool::Local per size class, made when first used).
  class Local {
   public:
    Local(PayloadStore* store, uint32_t batch) : store_(store), batch_(batch) {}
    Local(const Local&) = delete;
    Local& operator=(const Local&) = delete;
    // Stores C `values` as the payload that was `ref` (kNone: a new one); returns its reference,
    // which changes when the values no longer fit the slot.
    uint32_t store(uint32_t ref, const float* values);
    // A new payload equal to `ref`'s.
    uint32_t copy(uint32_t ref);
    void release(uint32_t ref);
    void flush();

   private:
    SlotPool::Local& pool(int size_class);
    uint32_t allocate(int size_class);

    PayloadStore* store_;
    uint32_t batch_;
    std::array<std::unique_ptr<SlotPool::Local>, kMaxSizeClasses> locals_;
  };

 private:
  static constexpr int kIndexBits = 28;
  static constexpr uint32_t kIndexMask = (1u << kIndexBits) - 1u;
  static int sizeClassOf(uint32_t ref) { return int(ref >> kIndexBits); }
  static uint32_t indexOf(uint32_t ref) { return ref & kIndexMask; }
  static uint32_t makeRef(int size_class, uint32_t index) {
    return (uint32_t(size_class) << kIndexBits) | index;
  }
  bool isDense(int size_class) const { return size_class == int(pools_.size()) - 1; }
  // Values a slot of the size class holds.
  int capacity(int size_class) const;
  // The smallest size class holding `count` values.
  int sizeClassFor(int count) const;
  // The values that differ from the prior as a sparse slot (mask, then those values) into
  // `sparse` (room for kMaxMaskWords + C floats); returns how many values it holds.
  int encode(const float* values, float* sparse) const;

  int num_classes_ = 1;
  float prior_ = 0.0f;
  int mask_words_ = 1;  // 32-bit words of the class mask of a sparse slot
  std::vector<std::unique_ptr<SlotPool>> pools_;
};

}  // namespace evidential_octomap
