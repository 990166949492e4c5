#include "projected_map.h"

#include <algorithm>
#include <stdexcept>

namespace evidential_octomap {
namespace {

nav_msgs::OccupancyGrid toMessage(const ProjectedGrid& grid, const std::string& frame_id) {
  nav_msgs::OccupancyGrid msg;
  msg.header.frame_id = frame_id;
  msg.info.resolution = static_cast<float>(grid.resolution);
  msg.info.width = grid.width;
  msg.info.height = grid.height;
  msg.info.origin.position.x = grid.origin_x;
  msg.info.origin.position.y = grid.origin_y;
  msg.info.origin.orientation.w = 1.0;
  msg.data = grid.cells;
  return msg;
}

}  // namespace

nav_msgs::OccupancyGrid projectOccupancy(const EvidentialOcTree& tree, const HeightBand& band,
                                         const std::string& frame_id) {
  return toMessage(evidential_octomap::projectOccupancy(tree, band.min_z, band.max_z), frame_id);
}

nav_msgs::OccupancyGrid projectClassCosts(const EvidentialOcTree& tree, const HeightBand& band,
                                          const std::vector<int8_t>& class_costs,
                                          int8_t no_class_cost, const std::string& frame_id) {
  return toMessage(evidential_octomap::projectClassCosts(tree, band.min_z, band.max_z,
                                                         class_costs, no_class_cost),
                   frame_id);
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
