// A map whose memory stays bounded over a long mission: the region around the robot stays in
// the tree, the rest is moved to disk as tiles and brought back when the robot returns.
//
// A tile is one octree node at a fixed depth (a cube of 2^k voxels, aligned with the keys), so a
// tile file holds exactly that node's subtree and no pruned block ever spans two tiles. A scan
// changes only voxels within its reach of the sensor (max_range plus the largest kernel
// support), and every tile within `radius` >= reach is in memory before the scan, so no scan
// ever changes a tile on disk: the global map (the tree merged with every tile) is the map that
// would have been built without tiles, voxel for voxel.
#pragma once

#include <octomap/octomap_types.h>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

class LocalMap {
 public:
  // `tree` (not owned) is the resident map; tiles go to `tile_directory` (created; it must hold
  // no tiles yet). radius [m]: tiles whose box is farther than radius + one tile edge from the
  // sensor are written out, tiles within radius are read back. Throws std::invalid_argument
  // when radius < reach(tree) (or the tree's max_range is unlimited), std::runtime_error when
  // the directory cannot be made or holds tiles.
  LocalMap(EvidentialOcTree* tree, const std::string& tile_directory, double radius);
  LocalMap(const LocalMap&) = delete;  // two owners of one tile directory would lose tiles
  LocalMap& operator=(const LocalMap&) = delete;

  // follow(origin_W), then the tree's insertSemanticScan.
  InsertStats insertSemanticScan(const octomap::Pointcloud& points_W,
                                 const std::vector<float>& evidence,
                                 const octomap::point3d& origin_W);
  // Writes out the tiles the sensor at origin_W has left and reads back those it approaches.
  // Throws std::invalid_argument, changing nothing, when the tree's settings now reach beyond
  // the radius (a raised max_range), std::runtime_error when a tile cannot be written (the
  // tile stays in memory) or read.
  void follow(const octomap::point3d& origin_W);
  // The whole map: a copy of the tree merged with every tile on disk (needs the whole map's
  // memory once).
  std::unique_ptr<EvidentialOcTree> globalMap() const;
  // The map that holds point_W, for queries: the resident tree, or the tile on disk that
  // contains the point, read from its file (the last kCachedTiles tiles read stay in memory, so
  // queries near each other read a tile once). The reference is valid until the next mapAt,
  // follow or insert. Throws std::runtime_error when that tile cannot be read. Not thread-safe.
  const EvidentialOcTree& mapAt(const octomap::point3d& point_W) const;
  static constexpr size_t kCachedTiles = 4;

  // How far [m] from the sensor one scan can change the map: max_range, the largest kernel
  // support and a voxel diagonal. < 0 for an unlimited max_range.
  static double reach(const EvidentialOcTree& tree);
  EvidentialOcTree& tree() const { return *tree_; }  // the resident map
  double radius() const { return radius_; }
  const std::string& directory() const { return directory_; }
  double tileEdge() const;  // [m]
  size_t tilesOnDisk() const { return on_disk_.size(); }
  size_t tilesWritten() const { return tiles_written_; }
  size_t tilesRead() const { return tiles_read_; }

  // The files of the tiles on disk (a snapshot links them: local_map_snapshot.h).
  std::vector<std::string> tileFiles() const;
  // Takes tiles another LocalMap of the same resolution and radius wrote (e.g. an autosave
  // snapshot's) as tiles on disk of this one: each file is linked (or copied) into the tile
  // directory; the tiles near the sensor come into the tree at the next follow. Throws
  // std::runtime_error, adopting none, when a name is not a tile of this map's tile size or the
  // tree already holds that tile.
  void adoptTiles(const std::vector<std::string>& files);

 private:
  using TileIndex = std::array<uint16_t, 3>;  // key >> (tree depth - tile depth), per axis
  TileIndex tileOf(const octomap::OcTreeKey& key) const;
  double distanceToTile(const octomap::point3d& p, const TileIndex& tile) const;
  std::string tilePath(const TileIndex& tile) const;
  void writeOut(const std::vector<TileIndex>& tiles);
  void readBack(const octomap::point3d& origin_W);

  EvidentialOcTree* tree_;
  std::string directory_;
  double radius_;
  unsigned tile_depth_;
  std::map<TileIndex, std::string> on_disk_;
  // Tiles on disk read by mapAt, oldest first; emptied whenever tiles move.
  mutable std::vector<std::pair<TileIndex, std::unique_ptr<EvidentialOcTree>>> cached_;
  size_t tiles_written_ = 0, tiles_read_ = 0;
};

}  // namespace evidential_octomap
