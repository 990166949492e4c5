// evidential_map_diff: how two semantic maps of the same scans differ, leaf by leaf (each map's
// leaves looked up in the other at the same key and depth): leaves missing from either, leaves
// whose occupancy differs, the largest absolute and relative difference of a payload value, and
// the labels that differ. For checking that a faster kernel keeps the map within its stated
// bound; a tool, not a test.
//
//   evidential_map_diff A.ot B.ot
#include <evidential_octomap/evidential_octree.h>
#include <evidential_octomap/io.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <vector>

namespace {

using evidential_octomap::EvidentialOcTree;

struct Diff {
  size_t leaves = 0, missing = 0, occupancy = 0, payload_presence = 0, labels = 0;
  double max_abs = 0.0, max_rel = 0.0;
};

// Every leaf of `a` against `b`; payload statistics only when `values` (once, for a -> b).
void compare(const EvidentialOcTree& a, const EvidentialOcTree& b, bool values, Diff* d) {
  const int num_classes = a.numClasses();
  for (auto it = a.begin_leafs(); it != a.end_leafs(); ++it) {
    ++d->leaves;
    const auto* other = b.search(it.getKey(), it.getDepth());
    if (!other) {
      ++d->missing;
      continue;
    }
    if (!values) continue;
    if (it->getLogOdds() != other->getLogOdds()) ++d->occupancy;
    const std::vector<float> pa = a.payload(&*it), pb = b.payload(other);
    if (pa.empty() != pb.empty()) {
      ++d->payload_presence;
      continue;
    }
    for (size_t c = 0; c < pa.size() && c < size_t(num_classes); ++c) {
      const double diff = std::fabs(double(pa[c]) - pb[c]);
      d->max_abs = std::max(d->max_abs, diff);
      if (std::fabs(pa[c]) > 1e-3) d->max_rel = std::max(d->max_rel, diff / std::fabs(pa[c]));
    }
    if (a.opinion(&*it).label != b.opinion(other).label) ++d->labels;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: evidential_map_diff A.ot B.ot\n");
    return 2;
  }
  try {
    const std::unique_ptr<EvidentialOcTree> a = evidential_octomap::loadMap(argv[1]);
    const std::unique_ptr<EvidentialOcTree> b = evidential_octomap::loadMap(argv[2]);
    if (a->numClasses() != b->numClasses()) throw std::runtime_error("class counts differ");
    Diff ab, ba;
    compare(*a, *b, true, &ab);
    compare(*b, *a, false, &ba);
    std::printf(
        "leaves: %zu in A, %zu in B; A's missing from B %zu, B's missing from A %zu\n"
        "occupancy differs: %zu; payload in one only: %zu\n"
        "max |payload difference|: %.3g (relative %.3g, values > 1e-3)\nlabels differ: %zu\n",
        ab.leaves, ba.leaves, ab.missing, ba.missing, ab.occupancy, ab.payload_presence, ab.max_abs,
        ab.max_rel, ab.labels);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "evidential_map_diff: %s\n", e.what());
    return 1;
  }
}
