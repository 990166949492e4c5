// Per-voxel majority labels of the mapped points (voxel_majority.h).
#include "voxel_majority.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace evidential_octomap::tools {

namespace {
using VoxelCounts =
    std::unordered_map<octomap::OcTreeKey, std::vector<uint32_t>, octomap::OcTreeKey::KeyHash>;

// Per voxel, how many mapped points carry each class (`labels[s]` of each mapped scan s; ignore
// class and out-of-range labels not counted).
VoxelCounts countLabels(const std::vector<Scan>& scans,
                        const std::vector<const std::vector<int>*>& labels,
                        const std::vector<size_t>& map_scans, const octomap::OcTree& keys_of,
                        int num_classes, int ignore_class) {
  VoxelCounts counts;
  for (size_t s : map_scans) {
    const Scan& scan = scans.at(s);
    const std::vector<int>& scan_labels = *labels.at(s);
    if (scan_labels.size() != scan.size()) continue;
    for (size_t i = 0; i < scan.size(); ++i) {
      const int c = scan_labels[i];
      if (c < 0 || c >= num_classes || c == ignore_class) continue;
      const Eigen::Vector3f p = scan.pointW(i);
      octomap::OcTreeKey key;
      if (!keys_of.coordToKeyChecked(octomap::point3d(p.x(), p.y(), p.z()), key)) continue;
      std::vector<uint32_t>& voxel = counts[key];
      if (voxel.empty()) voxel.assign(num_classes, 0);
      ++voxel[c];
    }
  }
  return counts;
}

std::vector<const std::vector<int>*> labelsOf(const std::vector<Scan>& scans, MajorityOf what) {
  std::vector<const std::vector<int>*> labels;
  for (const Scan& scan : scans)
    labels.push_back(what == MajorityOf::kPredictions ? &scan.predicted : &scan.gt);
  return labels;
}

std::vector<Query> majorityAnswers(const std::vector<Scan>& scans,
                                   const std::vector<const std::vector<int>*>& labels,
                                   const std::vector<size_t>& map_scans,
                                   const std::vector<Query>& queries, double resolution,
                                   int num_classes, int ignore_class) {
  const octomap::OcTree keys_of(resolution);  // only for coordToKeyChecked
  const VoxelCounts counts =
      countLabels(scans, labels, map_scans, keys_of, num_classes, ignore_class);
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
}  // namespace

std::vector<Query> voxelMajorityAnswers(const std::vector<Scan>& scans,
                                        const std::vector<size_t>& map_scans,
                                        const std::vector<Query>& queries, double resolution,
                                        int num_classes, int ignore_class, MajorityOf what) {
  return majorityAnswers(scans, labelsOf(scans, what), map_scans, queries, resolution,
                         num_classes, ignore_class);
}

std::vector<Query> voxelMajorityAnswers(const std::vector<Scan>& scans,
                                        const std::vector<std::vector<int>>& labels,
                                        const std::vector<size_t>& map_scans,
                                        const std::vector<Query>& queries, double resolution,
                                        int num_classes, int ignore_class) {
  std::vector<const std::vector<int>*> pointers;
  for (const std::vector<int>& l : labels) pointers.push_back(&l);
  return majorityAnswers(scans, pointers, map_scans, queries, resolution, num_classes,
                         ignore_class);
}

std::vector<std::vector<int>> evidenceLabels(const std::vector<std::vector<float>>& evidence,
                                             int num_classes) {
  std::vector<std::vector<int>> labels(evidence.size());
  for (size_t s = 0; s < evidence.size(); ++s) {
    const size_t n = evidence[s].size() / size_t(num_classes);
    labels[s].assign(n, -1);
    for (size_t i = 0; i < n; ++i) {
      const float* e = &evidence[s][i * num_classes];
      const float* best = std::max_element(e, e + num_classes);
      if (*best > 0.0f) labels[s][i] = int(best - e);
    }
  }
  return labels;
}

std::vector<Query> neighbourhoodOracleAnswers(const std::vector<Scan>& scans,
                                              const std::vector<size_t>& map_scans,
                                              const std::vector<Query>& queries, double resolution,
                                              double support, int num_classes, int ignore_class) {
  const octomap::OcTree keys_of(resolution);
  const VoxelCounts counts = countLabels(scans, labelsOf(scans, MajorityOf::kPredictions),
                                         map_scans, keys_of, num_classes, ignore_class);
  // Neighbour voxels whose cube lies within `support` of the query voxel's cube. A mapped point's
  // distance to the query voxel is at least that cube-to-cube gap, so this takes in every point
  // a kernel of that support could bring (and some more: the bound stays an upper bound).
  const int reach = int(std::ceil(support / resolution)) + 1;
  std::vector<std::array<int, 3>> offsets;
  for (int x = -reach; x <= reach; ++x)
    for (int y = -reach; y <= reach; ++y)
      for (int z = -reach; z <= reach; ++z) {
        const auto gap = [&](int d) { return std::max(0, std::abs(d) - 1) * resolution; };
        if (gap(x) * gap(x) + gap(y) * gap(y) + gap(z) * gap(z) <= support * support)
          offsets.push_back({x, y, z});
      }
  std::unordered_map<octomap::OcTreeKey, std::vector<uint32_t>, octomap::OcTreeKey::KeyHash>
      within;  // per query voxel: predictions within the support, summed
  std::vector<Query> answered = queries;
  for (Query& q : answered) {
    const int gt = q.gt;
    q.predicted = -1;
    octomap::OcTreeKey key;
    if (!keys_of.coordToKeyChecked(q.point_W, key)) continue;
    auto [it, fresh] = within.try_emplace(key);
    if (fresh) {
      it->second.assign(num_classes, 0);
      for (const auto& o : offsets) {
        const octomap::OcTreeKey n(key[0] + o[0], key[1] + o[1], key[2] + o[2]);
        const auto c = counts.find(n);
        if (c == counts.end()) continue;
        for (int k = 0; k < num_classes; ++k) it->second[k] += c->second[k];
      }
    }
    const std::vector<uint32_t>& near = it->second;
    const auto most = std::max_element(near.begin(), near.end());
    if (*most == 0) continue;
    q.predicted = (gt >= 0 && gt < num_classes && near[gt] > 0) ? gt : int(most - near.begin());
  }
  return answered;
}

}  // namespace evidential_octomap::tools
