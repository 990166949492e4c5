// Bench-only: how far two maps of the same rays differ in occupancy (the fast free-space mode
// against the exact one, or the exact semantic map against plain OctoMap). Leaves are weighted
// by their volume in finest voxels, so pruning differences do not count as differences.
#pragma once

#include <cstddef>

namespace evbench {

struct OccupancyDiff {
  size_t leaves_a = 0;             // leaves of a
  size_t leaves_differ = 0;        // leaves of a whose occupied/free state differs in b, or
                                   // that b does not know
  double known_a = 0.0;            // volume [voxels] known in a
  double known_b = 0.0;            // volume known in b
  double unknown_in_b = 0.0;       // volume known in a, unknown in b
  double unknown_in_a = 0.0;       // volume known in b, unknown in a
  double state_differs = 0.0;      // volume known in both, occupied in one and free in the other
  double occupied_a = 0.0, occupied_b = 0.0;  // occupied volume
};

// Compares every leaf of a with the node of b at the same key and depth (or the pruned leaf
// above it), then every leaf of b with a for the volume only b knows.
template <typename TreeA, typename TreeB>
OccupancyDiff occupancyDiff(const TreeA& a, const TreeB& b) {
  OccupancyDiff d;
  const unsigned depth = a.getTreeDepth();
  for (auto it = a.begin_leafs(), end = a.end_leafs(); it != end; ++it) {
    const double volume = double(1ull << (3 * (depth - it.getDepth())));
    const bool occupied = a.isNodeOccupied(*it);
    ++d.leaves_a;
    d.known_a += volume;
    if (occupied) d.occupied_a += volume;
    const auto* other = b.search(it.getKey(), it.getDepth());
    if (!other) {
      d.unknown_in_b += volume;
      ++d.leaves_differ;
    } else if (b.isNodeOccupied(*other) != occupied) {
      d.state_differs += volume;
      ++d.leaves_differ;
    }
  }
  for (auto it = b.begin_leafs(), end = b.end_leafs(); it != end; ++it) {
    const double volume = double(1ull << (3 * (depth - it.getDepth())));
    d.known_b += volume;
    if (b.isNodeOccupied(*it)) d.occupied_b += volume;
    if (!a.search(it.getKey(), it.getDepth())) d.unknown_in_a += volume;
  }
  return d;
}

}  // namespace evbench
