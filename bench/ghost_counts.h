// What the mover benches count in the volume a mover left: each voxel that rays have cleared
// since (plain OctoMap's log-odds below what it was then) is freed, and a freed voxel whose
// answer (EvidentialOcTree::answer, as a query sees it) is the mover's class is a ghost.
#pragma once

#include <octomap/OcTree.h>

#include <cstddef>

#include "evidential_octomap/evidential_octree.h"

namespace evbench {

struct GhostCounts {
  size_t freed = 0, ghosts = 0, own_ghosts = 0, free_ghosts = 0, occupied = 0, plain_occupied = 0;
  GhostCounts& operator+=(const GhostCounts& o) {
    freed += o.freed, ghosts += o.ghosts, own_ghosts += o.own_ghosts;
    free_ghosts += o.free_ghosts, occupied += o.occupied, plain_occupied += o.plain_occupied;
    return *this;
  }
};

// Counts the voxel at `key`, whose plain log-odds was `then` when the mover left it.
inline void countIfFreed(const evidential_octomap::EvidentialOcTree& tree,
                         const octomap::OcTree& plain, const octomap::OcTreeKey& key, float then,
                         int mover_class, GhostCounts* c) {
  const octomap::OcTreeNode* p = plain.search(key);
  if (!p || !(p->getLogOdds() < then)) return;  // no ray has cleared it since
  ++c->freed;
  c->plain_occupied += plain.isNodeOccupied(p);
  const auto* node = tree.search(key);
  c->occupied += node && tree.isNodeOccupied(node);
  const bool ghost = tree.answer(key).label == mover_class;
  c->ghosts += ghost;
  c->free_ghosts += ghost && !plain.isNodeOccupied(p);
  c->own_ghosts += tree.query(key).label == mover_class;
}

inline double share(size_t part, size_t whole) {
  return whole ? double(part) / double(whole) : 0.0;
}

}  // namespace evbench
