#include "consensus_labels.h"

#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace evidential_octomap::tools {
namespace {

// 21 bits per axis (±209 km at 0.2 m), enough for any sequence.
uint64_t voxelKey(const Eigen::Vector3f& p, double resolution) {
  const auto axis = [resolution](float v) {
    return static_cast<uint64_t>(static_cast<int64_t>(std::floor(v / resolution)) + (1 << 20)) &
           0x1FFFFFu;
  };
  return axis(p.x()) | axis(p.y()) << 21 | axis(p.z()) << 42;
}

int argmaxClass(const float* e, int num_classes) {
  int best = -1;
  float best_value = 0.0f;
  for (int c = 0; c < num_classes; ++c) {
    if (e[c] > best_value) {
      best_value = e[c];
      best = c;
    }
  }
  return best;
}

// Predicted class and voxel of every point of one scan.
struct ScanVotes {
  std::vector<uint64_t> voxels;
  std::vector<int> classes;
};

ScanVotes votesOf(const Scan& scan, const std::vector<float>& evidence, int C, double res) {
  ScanVotes v;
  v.voxels.resize(scan.size());
  v.classes.resize(scan.size());
  for (size_t i = 0; i < scan.size(); ++i) {
    v.voxels[i] = voxelKey(scan.pointW(i), res);
    v.classes[i] = evidence.size() == scan.size() * size_t(C)
                       ? argmaxClass(evidence.data() + i * C, C)
                       : -1;
  }
  return v;
}

}  // namespace

std::vector<std::vector<int>> consensusLabels(const std::vector<Scan>& scans,
                                              const std::vector<size_t>& which,
                                              const std::vector<std::vector<float>>& evidence,
                                              int num_classes, double resolution,
                                              int min_votes) {
  const int C = num_classes;
  std::vector<ScanVotes> votes;
  votes.reserve(which.size());
  for (size_t s : which) votes.push_back(votesOf(scans.at(s), evidence.at(s), C, resolution));
  // Every scan's votes per voxel and class, then each scan's own subtracted again.
  std::unordered_map<uint64_t, uint32_t> index;  // voxel -> row of `total`
  std::vector<uint32_t> total;
  for (const ScanVotes& v : votes) {
    for (size_t i = 0; i < v.voxels.size(); ++i) {
      if (v.classes[i] < 0) continue;
      const auto [it, added] = index.try_emplace(v.voxels[i], uint32_t(total.size() / C));
      if (added) total.resize(total.size() + C, 0);
      ++total[size_t(it->second) * C + v.classes[i]];
    }
  }
  std::vector<std::vector<int>> labels(scans.size());
  std::vector<uint32_t> own, others(C);
  for (size_t k = 0; k < which.size(); ++k) {
    const ScanVotes& v = votes[k];
    std::unordered_map<uint64_t, uint32_t> own_index;
    own.clear();
    for (size_t i = 0; i < v.voxels.size(); ++i) {
      if (v.classes[i] < 0) continue;
      const auto [it, added] = own_index.try_emplace(v.voxels[i], uint32_t(own.size() / C));
      if (added) own.resize(own.size() + C, 0);
      ++own[size_t(it->second) * C + v.classes[i]];
    }
    std::vector<int>& out = labels[which[k]];
    out.assign(v.voxels.size(), -1);
    for (size_t i = 0; i < v.voxels.size(); ++i) {
      const auto t = index.find(v.voxels[i]);
      if (t == index.end()) continue;
      const auto o = own_index.find(v.voxels[i]);
      int best = -1;
      uint32_t best_count = uint32_t(std::max(min_votes, 1)) - 1;
      for (int c = 0; c < C; ++c) {
        const uint32_t mine = o == own_index.end() ? 0 : own[size_t(o->second) * C + c];
        const uint32_t n = total[size_t(t->second) * C + c] - mine;
        if (n > best_count) {
          best_count = n;
          best = c;
        }
      }
      out[i] = best;
    }
  }
  return labels;
}

}  // namespace evidential_octomap::tools
