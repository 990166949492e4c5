// A map stored as tiles on disk: a directory of LocalMap's tile files (one octree node at a fixed
// depth each, tile_<depth>_<x>_<y>_<z>.ot) and a manifest, tiled_map.yaml, naming the
// resolution, tile depth, classes, rule, the adaptive cap's statistic and every tile. Written by
// the batch mapper (python -m evidential_octomap.batch), read here a tile at a time: a query
// loads only the tiles it touches, and the whole map streams into one .ot tile by tile.
#pragma once

#include <octomap/octomap_types.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

using TileIndex = std::array<uint16_t, 3>;  // key >> (tree depth - tile depth), per axis

// tile_<depth>_<x>_<y>_<z>.ot, the names LocalMap gives its tiles.
std::string tileFileName(unsigned depth, const TileIndex& tile);
// The depth and tile of such a name (a path's file name); false for any other name.
bool parseTileFileName(const std::string& path, unsigned* depth, TileIndex* tile);

struct TiledMapManifest {
  static constexpr const char* kFileName = "tiled_map.yaml";
  double resolution = 0.0;
  unsigned tile_depth = 0;
  std::vector<std::string> class_names;
  std::string rule;
  // The adaptive evidence cap's statistic of the whole map (sum over the mapped chunks).
  double evidence_log_sum = 0.0;
  uint64_t evidence_points = 0;
  std::vector<TileIndex> tiles;
};
// Writes <directory>/tiled_map.yaml atomically. Throws std::runtime_error.
void writeTiledMapManifest(const std::string& directory, const TiledMapManifest& manifest);
// Throws std::runtime_error when the file is missing or malformed.
TiledMapManifest readTiledMapManifest(const std::string& directory);

// What TiledMap::writeTiles moved out of a map.
struct WrittenTiles {
  std::vector<TileIndex> tiles;  // in file order of the whole map (depth first)
  double evidence_log_sum = 0.0;  // the map's adaptive-cap statistic
  uint64_t evidence_points = 0;
};

class TiledMap {
 public:
  // Reads the manifest of `directory`. Throws std::runtime_error when it is missing, malformed
  // or names a tile whose file is missing.
  explicit TiledMap(const std::string& directory);

  // Moves every node of `tree` at `tile_depth` (1..tree depth) into
  // <directory>/tile_<depth>_<x>_<y>_<z>.ot (each an atomic write of a map of the tree's
  // settings holding that subtree at its keys); pruned blocks above that depth are split first,
  // so the tiles hold every voxel. `tree` is empty afterwards. Throws std::runtime_error when a
  // file cannot be written, std::invalid_argument for a bad depth.
  static WrittenTiles writeTiles(EvidentialOcTree& tree, unsigned tile_depth,
                                 const std::string& directory);
  // The tile depth whose tile edge is the largest at most `edge` [m] (at least one voxel).
  static unsigned tileDepthForEdge(double resolution, double edge);

  const TiledMapManifest& manifest() const { return manifest_; }
  const std::string& directory() const { return directory_; }
  double tileEdge() const;  // [m]
  TileIndex tileOf(const octomap::OcTreeKey& key) const;
  std::string tilePath(const TileIndex& tile) const;
  bool hasTile(const TileIndex& tile) const;

  // One tile, read from its file, with the whole map's evidence statistic (it reads out as the
  // whole map does). Throws std::runtime_error when the file is unreadable or of another map.
  std::unique_ptr<EvidentialOcTree> loadTile(const TileIndex& tile) const;
  // The tiles that intersect the box [min, max], merged into one map.
  std::unique_ptr<EvidentialOcTree> region(const octomap::point3d& min_W,
                                           const octomap::point3d& max_W) const;
  // The map that answers queries at point_W as the whole map would: its tile (with the tiles
  // within a query's support of it when the map keeps evidence on the surface only), or an empty
  // map where there is no tile. The last kCachedTiles answers stay in memory; the reference is
  // valid until the next call. Not thread-safe.
  const EvidentialOcTree& mapAt(const octomap::point3d& point_W) const;
  static constexpr size_t kCachedTiles = 4;
  size_t tilesLoaded() const { return tiles_loaded_; }  // files read so far
  // A map of the tiled map's settings and statistic, without nodes (what mapAt answers from
  // where there is no tile).
  const EvidentialOcTree& emptyMap() const;

  // The whole map in memory (needs the whole map's memory).
  std::unique_ptr<EvidentialOcTree> globalMap() const;
  // The whole map as one .ot, written tile by tile: two passes over the tiles (node count and
  // log-odds table, then the nodes), holding one tile at a time; the bytes are saveMap's of
  // globalMap(). Throws std::runtime_error.
  void writeGlobalMap(const std::string& path) const;

 private:
  struct TileSummary;  // one tile's top node, for the structure above the tiles
  // A tile's file as stored (no evidence statistic), checked against the manifest.
  std::unique_ptr<EvidentialOcTree> readTile(const TileIndex& tile) const;
  // Every tile's top node and node count, in stream order; their log-odds into `table`.
  std::vector<TileSummary> summarize(LogOddsTable& table) const;
  // How many nodes the tiles [begin, end) and the nodes above them down from `depth` make.
  uint64_t countNodes(std::vector<TileSummary>::const_iterator begin,
                      std::vector<TileSummary>::const_iterator end, unsigned depth) const;
  // The nodes of tiles [begin, end), which share their ancestors down to `depth`.
  void writeNodes(std::vector<TileSummary>::const_iterator begin,
                  std::vector<TileSummary>::const_iterator end, unsigned depth,
                  const LogOddsTable& table, EvidentialOcTree::SectionWriter& out) const;

  std::string directory_;
  TiledMapManifest manifest_;
  std::vector<TileIndex> sorted_;  // manifest_.tiles sorted, for hasTile
  mutable std::vector<std::pair<TileIndex, std::unique_ptr<EvidentialOcTree>>> cached_;
  mutable std::unique_ptr<EvidentialOcTree> empty_;
  mutable size_t tiles_loaded_ = 0;
};

}  // namespace evidential_octomap
