#include "evidential_octomap/projected_grid.h"

#include <algorithm>

#include "evidential_octomap/detail/leaf_walk.h"

namespace evidential_octomap {
namespace {

// One leaf of the band as the grid needs it: its lowest x-y cell, its edge in cells, its mark.
struct Mark {
  octomap::key_type x, y;
  uint32_t cells;
  int8_t value;
};

// One walk of every leaf gives both the extent (all leaves) and the band's marks; the grid is
// filled once it is known how large it is.
template <typename MarkOf>
ProjectedGrid project(const EvidentialOcTree& tree, double min_z, double max_z, MarkOf mark_of) {
  ProjectedGrid grid;
  grid.resolution = tree.getResolution();
  const unsigned tree_depth = tree.getTreeDepth();
  uint32_t lo[2] = {UINT32_MAX, UINT32_MAX}, hi[2] = {0, 0};  // cells [lo, hi)
  std::vector<Mark> marks;
  detail::walkLeaves(
      tree, [](const EvidentialOcTreeNode&, unsigned) { return true; },
      [&](const EvidentialOcTreeNode& leaf, const octomap::OcTreeKey& corner, unsigned depth) {
        const uint32_t cells = uint32_t(1) << (tree_depth - depth);
        for (int a = 0; a < 2; ++a) {
          lo[a] = std::min<uint32_t>(lo[a], corner[a]);
          hi[a] = std::max<uint32_t>(hi[a], corner[a] + cells);
        }
        const double z = tree.keyToCoord(corner[2], depth);
        if (z >= min_z && z <= max_z) marks.push_back({corner[0], corner[1], cells, mark_of(leaf)});
      });
  if (lo[0] == UINT32_MAX) return grid;  // an empty map
  grid.width = hi[0] - lo[0];
  grid.height = hi[1] - lo[1];
  const double half = 0.5 * grid.resolution;
  grid.origin_x = tree.keyToCoord(octomap::key_type(lo[0])) - half;
  grid.origin_y = tree.keyToCoord(octomap::key_type(lo[1])) - half;
  grid.cells.assign(size_t(grid.width) * grid.height, -1);
  for (const Mark& m : marks) {
    for (uint32_t dy = 0; dy < m.cells; ++dy) {
      int8_t* row = &grid.cells[size_t(m.y - lo[1] + dy) * grid.width + (m.x - lo[0])];
      for (uint32_t dx = 0; dx < m.cells; ++dx) row[dx] = std::max(row[dx], m.value);
    }
  }
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
