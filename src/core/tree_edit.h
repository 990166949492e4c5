// Bookkeeping of one thread's edit of an EvidentialOcTree: the payloads it stores and gives
// back, and how many nodes it made or deleted. Threads editing disjoint subtrees each keep one
// and EvidentialOcTree::commit adds them up afterwards. Private to the core.
#pragma once

#include "evidential_octomap/evidential_octree.h"
#include "payload_store.h"

namespace evidential_octomap {

struct EvidentialOcTree::Edit {
  // batch: slots taken from the pool at a time (1 for serial edits, more for parallel ones).
  Edit(PayloadStore* store, uint32_t batch) : slots(store, batch) {}
  PayloadStore::Local slots;
  long long nodes = 0;  // created minus deleted
};

}  // namespace evidential_octomap
