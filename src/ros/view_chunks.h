// The views are read from the map in chunks: key-aligned cubes of the octree, each read in its
// own short hold of the map lock, so an insert waits for one chunk, never for the whole map.
// A chunk read after an insert shows that insert, one read before does not; the next publish
// pass shows it everywhere (the views are marked stale by every insert).
#pragma once

#include <vector>

#include "conversions.h"
#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// One cube of the octree, as an inclusive key range (the range of a node at kChunkDepth, or of
// a larger pruned leaf).
struct ViewChunk {
  octomap::OcTreeKey min, max;
};

// Chunk edge: 2^(tree depth - kChunkDepth) voxels (12.8 m at 0.2 m and tree depth 16).
constexpr unsigned kChunkDepth = 10;

// The chunks of `tree` that hold leaves and meet `box` (every one when the box is empty),
// clipped to the box. They are disjoint.
std::vector<ViewChunk> viewChunks(const EvidentialOcTree& tree, const Box& box);

// Appends the occupied (into `occupied`, when not null) and free (into `free`) leaves of one
// chunk whose centre lies in `band`. A leaf is read from the chunk its key lies in, so a leaf
// that spans chunks (pruned after the chunks were listed) is read once.
void readChunk(const EvidentialOcTree& tree, const ViewChunk& chunk, const HeightBand& band,
               std::vector<VoxelView>* occupied, std::vector<VoxelView>* free);

// Every occupied (free) leaf of `tree` with its key inside `box` (every leaf when the box is
// empty) and its centre in `band`, read chunk by chunk in one go.
std::vector<VoxelView> occupiedVoxels(const EvidentialOcTree& tree, const Box& box = Box(),
                                      const HeightBand& band = HeightBand());
std::vector<VoxelView> freeVoxels(const EvidentialOcTree& tree, const Box& box = Box(),
                                  const HeightBand& band = HeightBand());

}  // namespace evidential_octomap
