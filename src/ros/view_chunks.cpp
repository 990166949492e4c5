#include "view_chunks.h"

#include <algorithm>

namespace evidential_octomap {
namespace {

using octomap::OcTreeKey;

bool inRange(const OcTreeKey& key, const ViewChunk& range) {
  for (int i = 0; i < 3; ++i)
    if (key[i] < range.min[i] || key[i] > range.max[i]) return false;
  return true;
}

// The range clipped to `clip`; false when they do not meet.
bool clipTo(const ViewChunk& clip, ViewChunk* range) {
  for (int i = 0; i < 3; ++i) {
    range->min[i] = std::max(range->min[i], clip.min[i]);
    range->max[i] = std::min(range->max[i], clip.max[i]);
    if (range->min[i] > range->max[i]) return false;
  }
  return true;
}

// Descends from `node` (its cube's lowest key `base`, at `depth`) to kChunkDepth, or to a leaf
// above it, and lists each cube that meets `clip`.
void listChunks(const EvidentialOcTree& tree, const EvidentialOcTreeNode* node,
                const OcTreeKey& base, unsigned depth, const ViewChunk* clip,
                std::vector<ViewChunk>* out) {
  const unsigned half_edge_log2 = tree.getTreeDepth() - depth - 1;
  const unsigned edge = 2u << half_edge_log2;  // keys along one edge of this node's cube
  ViewChunk cube{base, base};
  for (int i = 0; i < 3; ++i) cube.max[i] = static_cast<uint16_t>(base[i] + edge - 1);
  if (clip && !clipTo(*clip, &cube)) return;
  if (depth == kChunkDepth || !tree.nodeHasChildren(node)) {
    out->push_back(cube);
    return;
  }
  for (unsigned c = 0; c < 8; ++c) {
    if (!tree.nodeChildExists(node, c)) continue;
    OcTreeKey child = base;  // octomap's child index: bit 0 x, bit 1 y, bit 2 z
    for (int i = 0; i < 3; ++i)
      if (c & (1u << i)) child[i] = static_cast<uint16_t>(child[i] + (1u << half_edge_log2));
    listChunks(tree, tree.getNodeChild(node, c), child, depth + 1, clip, out);
  }
}

}  // namespace

std::vector<ViewChunk> viewChunks(const EvidentialOcTree& tree, const Box& box) {
  std::vector<ViewChunk> chunks;
  if (tree.getRoot() == nullptr) return chunks;
  ViewChunk clip;
  if (!box.empty()) {
    const double lo = -tree.getResolution() * (1u << (tree.getTreeDepth() - 1));
    const double hi = -lo - tree.getResolution() / 2;
    octomap::point3d min = box.min, max = box.max;
    for (int i = 0; i < 3; ++i) {  // a box beyond the map's extent is clipped to it
      min(i) = float(std::clamp(double(min(i)), lo, hi));
      max(i) = float(std::clamp(double(max(i)), lo, hi));
    }
    clip.min = tree.coordToKey(min);
    clip.max = tree.coordToKey(max);
  }
  listChunks(tree, tree.getRoot(), OcTreeKey(0, 0, 0), 0, box.empty() ? nullptr : &clip,
             &chunks);
  return chunks;
}

void readChunk(const EvidentialOcTree& tree, const ViewChunk& chunk, const HeightBand& band,
               std::vector<VoxelView>* occupied, std::vector<VoxelView>* free) {
  if (tree.getRoot() == nullptr) return;
  for (auto it = tree.begin_leafs_bbx(chunk.min, chunk.max), end = tree.end_leafs_bbx();
       it != end; ++it) {
    if (!inRange(it.getKey(), chunk)) continue;  // read from the chunk that holds its key
    const octomap::point3d center = it.getCoordinate();
    if (!band.contains(center.z())) continue;
    std::vector<VoxelView>* into = tree.isNodeOccupied(*it) ? occupied : free;
    if (into) into->push_back(viewOfLeaf(tree, *it, center, it.getSize(), it.getDepth()));
  }
}

std::vector<VoxelView> occupiedVoxels(const EvidentialOcTree& tree, const Box& box,
                                      const HeightBand& band) {
  std::vector<VoxelView> voxels;
  for (const ViewChunk& chunk : viewChunks(tree, box)) readChunk(tree, chunk, band, &voxels, nullptr);
  return voxels;
}

std::vector<VoxelView> freeVoxels(const EvidentialOcTree& tree, const Box& box,
                                  const HeightBand& band) {
  std::vector<VoxelView> voxels;
  for (const ViewChunk& chunk : viewChunks(tree, box)) readChunk(tree, chunk, band, nullptr, &voxels);
  return voxels;
}

}  // namespace evidential_octomap
