#include "map_services.h"

#include <stdexcept>

#include "evidential_octomap/map_editing.h"

namespace evidential_octomap {
namespace {
octomap::point3d toPoint(const geometry_msgs::Point& p) { return octomap::point3d(p.x, p.y, p.z); }
}  // namespace

void answerQuery(const EvidentialOcTree& tree, const QueryMap::Request& req,
                 QueryMap::Response* res, const LocalMap* local) {
  const int C = tree.numClasses();
  const std::vector<std::string>& names = tree.classNames();
  res->num_classes = static_cast<uint16_t>(C);
  const size_t n = req.points.size();
  res->labels.reserve(n);
  res->uncertainties.reserve(n);
  res->occupancy.reserve(n);
  res->beliefs.reserve(n * C);
  for (const auto& p : req.points) {
    const EvidentialOcTree& map = local ? local->mapAt(toPoint(p)) : tree;
    const EvidentialOcTreeNode* node = map.nodeAt(toPoint(p));
    const VoxelOpinion o = map.query(toPoint(p));  // off the surface: the support answer
    res->labels.push_back(o.label);
    res->class_names.push_back(o.label >= 0 && o.label < int(names.size()) ? names[o.label] : "");
    res->uncertainties.push_back(o.uncertainty);
    res->conflicts.push_back(o.conflict);
    res->error_probabilities.push_back(map.rule().errorProbability(o));
    res->occupancy.push_back(node ? static_cast<float>(node->getOccupancy()) : -1.f);
    for (int c = 0; c < C; ++c) res->beliefs.push_back(c < int(o.belief.size()) ? o.belief[c] : 0.f);
  }
}

void clearBoxRequest(EvidentialOcTree* tree, const ClearBbx::Request& req,
                     ClearBbx::Response* res) {
  try {
    res->voxels_cleared = clearBox(tree, toPoint(req.min), toPoint(req.max));
    res->success = true;
    res->message = "cleared " + std::to_string(res->voxels_cleared) + " leaves";
  } catch (const std::invalid_argument& e) {
    res->voxels_cleared = 0;
    res->success = false;
    res->message = e.what();
  }
}

}  // namespace evidential_octomap
