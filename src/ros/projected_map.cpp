#include "projected_map.h"

#include <algorithm>
#include <stdexcept>

namespace evidential_octomap {
namespace {

// Walks every leaf whose centre is in `band` and hands `mark` the grid index of each cell under
// it. The grid spans the tree's metric x-y extent; keys give exact cell indices for leaves of
// any depth.
template <typename Mark>
nav_msgs::OccupancyGrid project(const EvidentialOcTree& tree, const HeightBand& band,
                                const std::string& frame_id, Mark mark) {
  nav_msgs::OccupancyGrid grid;
  grid.header.frame_id = frame_id;
  grid.info.resolution = static_cast<float>(tree.getResolution());
  grid.info.origin.orientation.w = 1.0;
  if (tree.getRoot() == nullptr) return grid;
  double min_x, min_y, min_z, max_x, max_y, max_z;
  tree.getMetricMin(min_x, min_y, min_z);
  tree.getMetricMax(max_x, max_y, max_z);
  const octomap::OcTreeKey min_key = tree.coordToKey(min_x, min_y, min_z);
  const octomap::OcTreeKey max_key = tree.coordToKey(max_x - 1e-6, max_y - 1e-6, max_z - 1e-6);
  grid.info.width = max_key[0] - min_key[0] + 1;
  grid.info.height = max_key[1] - min_key[1] + 1;
  const octomap::point3d origin = tree.keyToCoord(min_key);
  const double half = 0.5 * tree.getResolution();
  grid.info.origin.position.x = origin.x() - half;
  grid.info.origin.position.y = origin.y() - half;
  grid.data.assign(size_t(grid.info.width) * grid.info.height, -1);
  const unsigned depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!band.contains(it.getZ())) continue;
    const octomap::OcTreeKey corner = it.getIndexKey();
    const int cells = 1 << (depth - it.getDepth());
    for (int dx = 0; dx < cells; ++dx)
      for (int dy = 0; dy < cells; ++dy) {
        const size_t i = corner[0] + dx - min_key[0], j = corner[1] + dy - min_key[1];
        if (i < grid.info.width && j < grid.info.height)
          mark(*it, &grid.data[j * grid.info.width + i]);
      }
  }
  return grid;
}

}  // namespace

nav_msgs::OccupancyGrid projectOccupancy(const EvidentialOcTree& tree, const HeightBand& band,
                                         const std::string& frame_id) {
  return project(tree, band, frame_id, [&](const EvidentialOcTreeNode& leaf, int8_t* cell) {
    if (tree.isNodeOccupied(leaf))
      *cell = 100;
    else if (*cell == -1)
      *cell = 0;
  });
}

nav_msgs::OccupancyGrid projectClassCosts(const EvidentialOcTree& tree, const HeightBand& band,
                                          const std::vector<int8_t>& class_costs,
                                          int8_t no_class_cost, const std::string& frame_id) {
  return project(tree, band, frame_id, [&](const EvidentialOcTreeNode& leaf, int8_t* cell) {
    if (!tree.isNodeOccupied(leaf)) {
      if (*cell == -1) *cell = 0;
      return;
    }
    const int label = leaf.hasSemantics() ? tree.opinion(&leaf).label : -1;
    const int8_t cost =
        label >= 0 && label < int(class_costs.size()) ? class_costs[label] : no_class_cost;
    *cell = std::max(*cell, cost);
  });
}

std::vector<int8_t> classCosts(const ClassTable& classes,
                               const std::vector<std::pair<std::string, int>>& table,
                               int default_cost) {
  auto checked = [](const std::string& what, int cost) {
    if (cost < 0 || cost > 100)
      throw std::invalid_argument(what + ": cost " + std::to_string(cost) + " is outside 0..100");
    return static_cast<int8_t>(cost);
  };
  std::vector<int8_t> costs(classes.names.size(), checked("default cost", default_cost));
  for (const auto& [name, cost] : table) {
    const auto it = std::find(classes.names.begin(), classes.names.end(), name);
    if (it == classes.names.end())
      throw std::invalid_argument("class_costs: '" + name + "' is not a class of the table");
    costs[it - classes.names.begin()] = checked("class_costs/" + name, cost);
  }
  return costs;
}

}  // namespace evidential_octomap
