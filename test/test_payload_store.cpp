// PayloadStore, the sparse store of semantic payloads: after any sequence of stores, copies and
// releases every payload decodes to exactly (bit for bit) the C floats last stored, its sum is
// the class-order sum of those floats, holdsAny tells which classes differ from the prior's
// bits, and a payload costs the slot of its non-prior classes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "payload_store.h"

namespace evidential_octomap {
namespace {

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), 4 * a.size()) == 0;
}

// Values where a random share of classes keeps the prior; the others are random, among them
// values that equal the prior but not its bits (-0.0 against 0.0), denormals and huge values.
std::vector<float> randomValues(std::mt19937& rng, int num_classes, float prior, double dense) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<float> v(num_classes, prior);
  for (float& x : v) {
    if (unit(rng) >= dense) continue;
    const double kind = unit(rng);
    if (kind < 0.05) {
      x = -prior;  // -0.0 for the dempster prior
    } else if (kind < 0.1) {
      x = std::numeric_limits<float>::denorm_min();
    } else if (kind < 0.15) {
      x = std::numeric_limits<float>::max();
    } else {
      x = prior + float(unit(rng) * 10.0);
    }
  }
  return v;
}

TEST(PayloadStore, RandomSequencesDecodeToTheDenseReference) {
  for (int num_classes : {1, 2, 3, 20, 32, 33, 64, 255}) {
    for (float prior : {0.0f, 0.001f, 1.0f}) {
      std::mt19937 rng(num_classes * 7 + int(prior * 1000));
      PayloadStore store(num_classes, prior);
      PayloadStore::Local local(&store, 16);
      std::vector<uint32_t> refs;
      std::vector<std::vector<float>> reference;  // the dense payload of each ref
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      for (int step = 0; step < 3000; ++step) {
        const double op = unit(rng);
        const size_t pick = refs.empty() ? 0 : rng() % refs.size();
        // Mostly sparse payloads that grow, now and then a dense one.
        const double dense = unit(rng) < 0.1 ? 1.0 : unit(rng) * 0.3;
        if (refs.empty() || op < 0.3) {  // new payload
          reference.push_back(randomValues(rng, num_classes, prior, dense));
          refs.push_back(local.store(PayloadStore::kNone, reference.back().data()));
        } else if (op < 0.75) {  // overwrite (may grow and move)
          reference[pick] = randomValues(rng, num_classes, prior, dense);
          refs[pick] = local.store(refs[pick], reference[pick].data());
        } else if (op < 0.85) {  // copy
          refs.push_back(local.copy(refs[pick]));
          reference.push_back(reference[pick]);
        } else {  // release
          local.release(refs[pick]);
          refs.erase(refs.begin() + pick);
          reference.erase(reference.begin() + pick);
        }
      }
      local.flush();
      ASSERT_EQ(store.inUse(), refs.size());
      std::vector<float> decoded(num_classes);
      for (size_t i = 0; i < refs.size(); ++i) {
        store.decode(refs[i], decoded.data());
        ASSERT_TRUE(sameBits(decoded, reference[i])) << "C " << num_classes << " prior " << prior;
        const double sum = std::accumulate(reference[i].begin(), reference[i].end(), 0.0);
        ASSERT_EQ(store.sum(refs[i]), sum) << "C " << num_classes << " prior " << prior;
        // holdsAny against the reference's bits, for one class and for a random set.
        const int c = int(rng() % num_classes);
        std::vector<uint32_t> one((num_classes + 31) / 32, 0), some(one.size(), 0);
        one[c / 32] = uint32_t(1) << (c % 32);
        bool any = false;
        for (int k = 0; k < num_classes; ++k) {
          if (rng() % 4) continue;
          some[k / 32] |= uint32_t(1) << (k % 32);
          any |= std::memcmp(&reference[i][k], &prior, sizeof(float)) != 0;
        }
        ASSERT_EQ(store.holdsAny(refs[i], one.data()),
                  std::memcmp(&reference[i][c], &prior, sizeof(float)) != 0);
        ASSERT_EQ(store.holdsAny(refs[i], some.data()), any);
      }
    }
  }
}

TEST(PayloadStore, APayloadCostsItsNonPriorClassesNotC) {
  const int num_classes = 20;
  const int count = 100000;
  PayloadStore store(num_classes, 0.0f);
  {
    PayloadStore::Local local(&store, 256);
    std::vector<float> values(num_classes, 0.0f);
    for (int i = 0; i < count; ++i) {
      values[i % num_classes] = 1.0f + float(i);  // two classes set: a slot of 2 values
      values[(i + 7) % num_classes] = 2.0f;
      local.store(PayloadStore::kNone, values.data());
      values[i % num_classes] = values[(i + 7) % num_classes] = 0.0f;
    }
  }
  EXPECT_EQ(store.inUse(), size_t(count));
  // One mask word and two values (12 B) a payload, plus at most one partly used block per size
  // class; the dense store would take 80 B.
  const size_t slack = 6 * SlotPool::kBlockSlots * num_classes * sizeof(float);
  EXPECT_LE(store.bytes(), size_t(count) * 12 + slack);
  EXPECT_GE(store.bytes(), size_t(count) * 12);
}

TEST(PayloadStore, APayloadThatOutgrowsItsSlotMovesAndFreesTheOldOne) {
  PayloadStore store(20, 0.0f);
  PayloadStore::Local local(&store, 1);
  std::vector<float> values(20, 0.0f);
  values[3] = 1.0f;
  uint32_t ref = local.store(PayloadStore::kNone, values.data());
  const uint32_t small = ref;
  values[4] = 2.0f;
  values[19] = 3.0f;
  ref = local.store(ref, values.data());  // 3 values: a slot of 4
  EXPECT_NE(ref, small);
  values[4] = 5.0f;
  EXPECT_EQ(local.store(ref, values.data()), ref);  // still fits: stays
  // The freed slot of 1 value is the next one handed out for 1 value.
  std::vector<float> one(20, 0.0f);
  one[0] = 1.0f;
  EXPECT_EQ(local.store(PayloadStore::kNone, one.data()), small);
  local.flush();
  EXPECT_EQ(store.inUse(), 2u);
  std::vector<float> decoded(20);
  store.decode(ref, decoded.data());
  EXPECT_TRUE(sameBits(decoded, values));
}

}  // namespace
}  // namespace evidential_octomap
