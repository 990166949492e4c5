#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/map_editing.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace evidential_octomap {

std::string boxProblem(const octomap::point3d& min, const octomap::point3d& max) {
  static const char kAxes[] = "xyz";
  for (int i = 0; i < 3; ++i) {
    std::ostringstream s;
    if (!std::isfinite(min(i)) || !std::isfinite(max(i))) {
      s << "box corner " << kAxes[i] << " is not finite (min " << min(i) << ", max " << max(i)
        << ")";
      return s.str();
    }
    if (min(i) > max(i)) {
      s << "box is inverted: min " << kAxes[i] << " = " << min(i) << " > max " << kAxes[i]
        << " = " << max(i);
      return s.str();
    }
  }
  return "";
}

// Leaves are not deleted: OctoMap 1.9's deleteNode frees an emptied parent without its child
// array, which trips an assertion in Debian's liboctomap.
uint32_t clearBox(EvidentialOcTree* tree, const octomap::point3d& min, const octomap::point3d& max) {
  const std::string problem = boxProblem(min, max);
  if (!problem.empty()) throw std::invalid_argument("clear box refused: " + problem);
  if (tree->getRoot() == nullptr) return 0;
  const double lim = tree->getResolution() * 32767.0;
  auto clampPoint = [&](octomap::point3d p) {
    for (int i = 0; i < 3; ++i) p(i) = std::max<float>(-lim, std::min<float>(lim, p(i)));
    return p;
  };
  octomap::OcTreeKey kmin, kmax;
  if (!tree->coordToKeyChecked(clampPoint(min), kmin) || !tree->coordToKeyChecked(clampPoint(max), kmax))
    return 0;
  const unsigned max_depth = tree->getTreeDepth();
  std::vector<std::pair<octomap::OcTreeKey, unsigned>> targets;
  for (auto it = tree->begin_leafs_bbx(kmin, kmax), end = tree->end_leafs_bbx(); it != end; ++it) {
    const unsigned depth = it.getDepth();
    const octomap::OcTreeKey k = it.getKey();
    if (depth == max_depth) {
      targets.emplace_back(k, depth);
      continue;
    }
    // A coarse leaf spans keys [k - half, k + half - 1] on each axis.
    const unsigned half = 1u << (max_depth - depth - 1);
    unsigned lo[3], hi[3];
    bool inside = true;
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::max<unsigned>(k[i] - half, kmin[i]);
      hi[i] = std::min<unsigned>(k[i] + half - 1, kmax[i]);
      inside = inside && lo[i] == unsigned(k[i] - half) && hi[i] == unsigned(k[i] + half - 1);
    }
    if (inside) {
      targets.emplace_back(k, depth);
      continue;
    }
    for (unsigned x = lo[0]; x <= hi[0]; ++x)
      for (unsigned y = lo[1]; y <= hi[1]; ++y)
        for (unsigned z = lo[2]; z <= hi[2]; ++z)
          targets.emplace_back(octomap::OcTreeKey(x, y, z), max_depth);
  }
  uint32_t cleared = 0;
  for (const auto& target : targets) {
    EvidentialOcTreeNode* node = target.second == max_depth
                                     ? detail::TreeEditing::leafForUpdate(*tree, target.first, false)
                                     : tree->search(target.first, target.second);
    if (!node) continue;
    node->setLogOdds(tree->getClampingThresMinLog());
    detail::TreeEditing::clearPayload(*tree, node);
    ++cleared;
  }
  detail::TreeEditing::updateInnerNodes(*tree);
  return cleared;
}

}  // namespace evidential_octomap
