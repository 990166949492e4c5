// Per-voxel majority labels of the mapped points (voxel_majority.h).
#include "voxel_majority.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <unordered_map>

namespace evidential_octomap::tools {

std::vector<Query> voxelMajorityAnswers(const std::vector<Scan>& scans,
                                        const std::vector<size_t>& map_scans,
                                        const std::vector<Query>& queries, double resolution,
                                        int num_classes, int ignore_class, MajorityOf what) {
  const octomap::OcTree keys_of(resolution);  // only for coordToKeyChecked
  std::unordered_map<octomap::OcTreeKey, std::vector<uint32_t>, octomap::OcTreeKey::KeyHash> counts;
  for (size_t s : map_scans) {
    const Scan& scan = scans.at(s);
    const std::vector<int>& labels = what == MajorityOf::kPredictions ? scan.predicted : scan.gt;
    if (labels.size() != scan.size()) continue;
    for (size_t i = 0; i < scan.size(); ++i) {
      const int c = labels[i];
      if (c < 0 || c >= num_classes || c == ignore_class) continue;
      const Eigen::Vector3f p = scan.pointW(i);
      octomap::OcTreeKey key;
      if (!keys_of.coordToKeyChecked(octomap::point3d(p.x(), p.y(), p.z()), key)) continue;
      std::vector<uint32_t>& voxel = counts[key];
      if (voxel.empty()) voxel.assign(num_classes, 0);
      ++voxel[c];
    }
  }
  std::vector<Query> answered = queries;
  for (Query& q : answered) {
    q.predicted = -1;
    octomap::OcTreeKey key;
    if (!keys_of.coordToKeyChecked(q.point_W, key)) continue;
    const auto it = counts.find(key);
    if (it == counts.end()) continue;
    q.predicted = int(std::max_element(it->second.begin(), it->second.end()) - it->second.begin());
  }
  return answered;
}

}  // namespace evidential_octomap::tools
