#include "evidential_octomap/projected_grid.h"

#include <algorithm>

#include "evidential_octomap/detail/leaf_walk.h"

namespace evidential_octomap {
namespace {

// The least (or, `largest`, the largest end) cell along x-y axis `axis` that a leaf below
// `node` covers, improving on `best`: subtrees that cannot improve it are not entered, so the
// search follows the map's edge instead of visiting every leaf.
void extentAlong(const EvidentialOcTree& tree, const EvidentialOcTreeNode* node,
                 octomap::OcTreeKey corner, unsigned depth, int axis, bool largest,
                 uint32_t* best) {
  const uint32_t size = uint32_t(1) << (tree.getTreeDepth() - depth);
  const uint32_t lo = corner[axis], hi = lo + size;
  if (largest ? hi <= *best : lo >= *best) return;
  if (!tree.nodeHasChildren(node)) {
    *best = largest ? hi : lo;
    return;
  }
  const octomap::key_type half = octomap::key_type(size / 2);
  // The children on the side of the edge sought first: a leaf found there bounds the others.
  for (unsigned side : {unsigned(largest), unsigned(!largest)}) {
    for (unsigned i = 0; i < 8; ++i) {
      if ((i >> axis & 1u) != side || !tree.nodeChildExists(node, i)) continue;
      octomap::OcTreeKey child = corner;
      for (unsigned a = 0; a < 3; ++a)
        if (i & (1u << a)) child[a] = octomap::key_type(child[a] + half);
      extentAlong(tree, tree.getNodeChild(node, i), child, depth + 1, axis, largest, best);
    }
  }
}

// The grid over the x-y extent of every leaf (found along the map's edges), filled in one walk
// of the leaves whose centre lies in the band.
template <typename MarkOf>
ProjectedGrid project(const EvidentialOcTree& tree, double min_z, double max_z, MarkOf mark_of) {
  ProjectedGrid grid;
  grid.resolution = tree.getResolution();
  const EvidentialOcTreeNode* root = tree.getRoot();
  if (root == nullptr) return grid;  // an empty map
  const octomap::OcTreeKey origin(0, 0, 0);
  uint32_t lo[2] = {UINT32_MAX, UINT32_MAX}, hi[2] = {0, 0};  // cells [lo, hi)
  for (int a = 0; a < 2; ++a) {
    extentAlong(tree, root, origin, 0, a, false, &lo[a]);
    extentAlong(tree, root, origin, 0, a, true, &hi[a]);
  }
  grid.width = hi[0] - lo[0];
  grid.height = hi[1] - lo[1];
  const double half = 0.5 * grid.resolution;
  grid.origin_x = tree.keyToCoord(octomap::key_type(lo[0])) - half;
  grid.origin_y = tree.keyToCoord(octomap::key_type(lo[1])) - half;
  grid.cells.assign(size_t(grid.width) * grid.height, -1);
  const unsigned tree_depth = tree.getTreeDepth();
  detail::walkLeaves(
      tree, [](const EvidentialOcTreeNode&, const octomap::OcTreeKey&, unsigned) { return true; },
      [&](const EvidentialOcTreeNode& leaf, const octomap::OcTreeKey& corner, unsigned depth) {
        const double z = tree.keyToCoord(corner[2], depth);
        if (!(z >= min_z && z <= max_z)) return;
        const uint32_t cells = uint32_t(1) << (tree_depth - depth);
        const int8_t value = mark_of(leaf);
        int8_t* first = &grid.cells[size_t(corner[1] - lo[1]) * grid.width + (corner[0] - lo[0])];
        for (uint32_t dy = 0; dy < cells; ++dy) {
          int8_t* row = first + size_t(dy) * grid.width;
          for (uint32_t dx = 0; dx < cells; ++dx) row[dx] = std::max(row[dx], value);
        }
      });
  return grid;
}

}  // namespace

ProjectedGrid projectOccupancy(const EvidentialOcTree& tree, double min_z, double max_z) {
  return project(tree, min_z, max_z, [&](const EvidentialOcTreeNode& leaf) -> int8_t {
    return tree.isNodeOccupied(leaf) ? 100 : 0;
  });
}

ProjectedGrid projectClassCosts(const EvidentialOcTree& tree, double min_z, double max_z,
                                const std::vector<int8_t>& class_costs, int8_t no_class_cost) {
  return project(tree, min_z, max_z, [&](const EvidentialOcTreeNode& leaf) -> int8_t {
    if (!tree.isNodeOccupied(leaf)) return 0;
    const int label = leaf.hasSemantics() ? tree.opinion(&leaf).label : -1;
    return label >= 0 && label < int(class_costs.size()) ? class_costs[label] : no_class_cost;
  });
}

}  // namespace evidential_octomap
