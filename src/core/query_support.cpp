// Queries off the surface (docs/design.md): in a map that keeps its evidence on the surface
// (SemanticConfig::semantic_occupied_only), a known voxel without evidence of its own is
// answered from the voxels with evidence within a point's full kernel support around it.
// Each neighbour's stored values (less the rule's prior) are weighted by the sparse kernel of
// the distance from the query voxel's centre to the neighbour's cube; the answer is the
// kernel-weighted mean of those values, discounted by the kernel weight of the nearest one
// (a voxel next to the surface answers almost as the surface does, one at the edge of the
// support with little evidence). It is read out only: nothing is stored, so the answer is a
// function of the stored sums and a merged map answers from its merged evidence. A free voxel's
// own evidence of a movable class is answered only beside a surface of that class.
#include <algorithm>
#include <cmath>

#include "evidential_octomap/detail/leaf_walk.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/sparse_kernel.h"

namespace evidential_octomap {

std::array<int, 3> EvidentialOcTree::querySupportReach() const {
  const double length = queryLength();
  const double extra = config_.kernel_distance == "voxel" ? 1.0 : 0.5;
  const int across = static_cast<int>(std::floor(length / resolution + extra));
  const int up =
      static_cast<int>(std::floor(length * querySupportVertical() / resolution + extra));
  return {across, across, up};
}

// The tallest support of any neighbour.
double EvidentialOcTree::querySupportVertical() const {
  return ground_classes_.empty()
             ? config_.vertical_support
             : std::max(config_.vertical_support, config_.ground_vertical_support);
}

double EvidentialOcTree::queryLength() const {
  // The support of a point without uncertainty: the farthest any point reaches.
  return rule_->usesUncertaintyKernel()
             ? adaptiveLength(config_.length_scale, config_.beta, config_.effectiveGamma(), 0.0)
             : config_.length_scale;
}

bool EvidentialOcTree::supportPayload(const octomap::OcTreeKey& key, bool free_voxel,
                                      float* out) const {
  const std::array<int, 3> reach = querySupportReach();
  const double widest = querySupportVertical();
  const double length = queryLength();
  const double half = config_.kernel_distance == "voxel" ? resolution / 2.0 : 0.0;
  const float prior = rule_->prior();
  double sum[kMaxClasses] = {};
  double weight_sum = 0.0, nearest = 0.0;
  float values[kMaxClasses];
  bool answered[kMaxClasses];
  for (int c = 0; c < num_classes_; ++c) answered[c] = !(free_voxel && clearsMovable(c));
  for (int dz = -reach[2]; dz <= reach[2]; ++dz) {
    for (int dy = -reach[1]; dy <= reach[1]; ++dy) {
      for (int dx = -reach[0]; dx <= reach[0]; ++dx) {
        if (!dx && !dy && !dz) continue;
        const int x = int(key[0]) + dx, y = int(key[1]) + dy, z = int(key[2]) + dz;
        if (std::min({x, y, z}) < 0 || std::max({x, y, z}) > 0xFFFF) continue;
        const auto weight = [&](double up) {
          const double d =
              kernelDistance(dx * resolution, dy * resolution, dz * resolution, half, up);
          // The kernel's shape only: the stored evidence already carries each point's
          // reliability (sigma0), so weighing it by sigma0 again would discount it twice.
          return sparseKernel(d, length, 1.0);
        };
        const double k_widest = weight(widest);
        if (!(k_widest > 0.0)) continue;
        if (!payload(search(octomap::OcTreeKey(x, y, z)), values)) continue;
        // A neighbour of a ground class reaches as far up as its points did.
        const int label = int(std::max_element(values, values + num_classes_) - values);
        const double up =
            isGroundClass(label) ? config_.ground_vertical_support : config_.vertical_support;
        const double k = up == widest ? k_widest : weight(up);
        if (!(k > 0.0)) continue;
        for (int c = 0; c < num_classes_; ++c)
          if (answered[c]) sum[c] += k * (double(values[c]) - prior);
        weight_sum += k;
        nearest = std::max(nearest, k);
      }
    }
  }
  if (!(weight_sum > 0.0)) return false;
  const double scale = nearest / weight_sum;
  for (int c = 0; c < num_classes_; ++c) out[c] = prior + float(scale * sum[c]);
  return true;
}

// A free voxel's evidence of a movable class came from the kernel of points on an object beside
// it. While the object is there its surface answers the class; once its voxels are cleared the
// evidence left in free space is a ghost of it, so the class is not answered there. The surface
// is looked for among the occupied leaves within the support: a walk that enters only occupied
// subtrees overlapping it, and stops once every class has one.
void EvidentialOcTree::dropMovableWithoutSurface(const octomap::OcTreeKey& key,
                                                 float* values) const {
  const float prior = rule_->prior();
  bool ghost[kMaxClasses];
  int ghosts = 0;
  for (int c = 0; c < num_classes_; ++c)
    ghosts += ghost[c] = clearsMovable(c) && values[c] > prior;
  if (!ghosts) return;
  const std::array<int, 3> reach = querySupportReach();
  const double length = queryLength();
  const double half = config_.kernel_distance == "voxel" ? resolution / 2.0 : 0.0;
  const unsigned depth_max = getTreeDepth();
  // The offset from `key` to the block's cell nearest it, per axis [voxels].
  const auto nearest = [&](const octomap::OcTreeKey& corner, unsigned depth, int a) {
    const int lo = corner[a], hi = lo + (1 << (depth_max - depth)) - 1;
    return std::clamp(int(key[a]), lo, hi) - int(key[a]);
  };
  const auto within = [&](const octomap::OcTreeKey& corner, unsigned depth) {
    for (int a = 0; a < 3; ++a)
      if (std::abs(nearest(corner, depth, a)) > reach[a]) return false;
    return true;
  };
  float leaf_values[kMaxClasses];
  detail::walkLeaves(
      *this,
      [&](const EvidentialOcTreeNode& node, const octomap::OcTreeKey& corner, unsigned depth) {
        return ghosts > 0 && isNodeOccupied(node) && within(corner, depth);
      },
      [&](const EvidentialOcTreeNode& leaf, const octomap::OcTreeKey& corner, unsigned depth) {
        if (!ghosts || !isNodeOccupied(leaf) || !payload(&leaf, leaf_values)) return;
        const int label = int(std::max_element(leaf_values, leaf_values + num_classes_) -
                              leaf_values);
        if (!ghost[label]) return;
        const double up =
            isGroundClass(label) ? config_.ground_vertical_support : config_.vertical_support;
        const double d = kernelDistance(nearest(corner, depth, 0) * resolution,
                                        nearest(corner, depth, 1) * resolution,
                                        nearest(corner, depth, 2) * resolution, half, up);
        if (sparseKernel(d, length, 1.0) > 0.0) ghost[label] = false, --ghosts;
      });
  for (int c = 0; c < num_classes_; ++c)
    if (ghost[c]) values[c] = prior;
}

bool EvidentialOcTree::answerPayload(const octomap::OcTreeKey& key, float* out) const {
  const EvidentialOcTreeNode* node = search(key);
  if (!node) return false;  // unknown space: no answer
  if (payload(node, out)) {
    if (!isNodeOccupied(node)) dropMovableWithoutSurface(key, out);
    return true;
  }
  // Only a map that keeps its evidence on the surface answers free space from it: in the
  // default map free space near surfaces holds evidence of its own, and a voxel without any
  // (beyond every support, or cleared by clearBox) has no answer.
  return config_.semantic_occupied_only && supportPayload(key, !isNodeOccupied(node), out);
}

VoxelOpinion EvidentialOcTree::answer(const octomap::OcTreeKey& key) const {
  float values[kMaxClasses];
  if (!answerPayload(key, values)) std::fill_n(values, num_classes_, rule_->prior());
  return rule_->readout(values, num_classes_);
}

}  // namespace evidential_octomap
