#include "evidential_octomap/local_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/safe_key.h"

namespace evidential_octomap {

namespace fs = std::filesystem;

namespace {
// Tile files are named tile_<depth>_<x>_<y>_<z>.ot; anything else in the directory is left alone.
bool isTileFile(const fs::path& p) {
  const std::string name = p.filename().string();
  return name.rfind("tile_", 0) == 0 && p.extension() == ".ot";
}
}  // namespace

double LocalMap::reach(const EvidentialOcTree& tree) {
  const double max_range = tree.config().max_range;
  if (!(max_range > 0.0)) return -1.0;
  const double res = tree.getResolution();
  return max_range + SemanticConfig::kMaxSupportLeaves * res + std::sqrt(3.0) * res;
}

namespace {
// "" when one scan from a sensor cannot change what lies beyond `radius`, else why.
std::string radiusProblem(const EvidentialOcTree& tree, double radius) {
  const double r = LocalMap::reach(tree);
  std::ostringstream why;
  if (r < 0.0) {
    why << "a local map needs a finite max_range (the reach of a scan), got "
        << tree.config().max_range;
  } else if (!(radius >= r)) {
    why << "local map radius " << radius << " m must be at least the reach of a scan, " << r
        << " m (max_range " << tree.config().max_range << " m + the largest kernel support + "
        << "a voxel diagonal)";
  }
  return why.str();
}
}  // namespace

LocalMap::LocalMap(EvidentialOcTree* tree, const std::string& tile_directory, double radius)
    : tree_(tree), directory_(tile_directory), radius_(radius) {
  const std::string problem = radiusProblem(*tree, radius);
  if (!problem.empty()) throw std::invalid_argument(problem);
  // The largest tile whose edge is at most radius / 2, so the map in memory stays within about
  // 1.5 radius of the sensor.
  const unsigned depth = tree->getTreeDepth();
  tile_depth_ = depth;
  while (tile_depth_ > 1 && tree->getNodeSize(tile_depth_ - 1) <= radius / 2.0) --tile_depth_;
  std::error_code ec;
  fs::create_directories(directory_, ec);
  if (ec)
    throw std::runtime_error("cannot make tile directory " + directory_ + ": " + ec.message());
  for (const auto& entry : fs::directory_iterator(directory_)) {
    if (isTileFile(entry.path())) {
      throw std::runtime_error("tile directory " + directory_ + " holds tiles of another map (" +
                               entry.path().filename().string() + "); give an empty one");
    }
  }
}

double LocalMap::tileEdge() const { return tree_->getNodeSize(tile_depth_); }

double LocalMap::distanceToTile(const octomap::point3d& p, const TileIndex& tile) const {
  const double edge = tileEdge();
  const unsigned shift = tree_->getTreeDepth() - tile_depth_;
  double squared = 0.0;
  for (int i = 0; i < 3; ++i) {
    // The tile's first key, its voxel's lower face, then the box [lo, lo + edge].
    const octomap::key_type first = static_cast<octomap::key_type>(tile[i] << shift);
    const double lo = tree_->keyToCoord(first) - 0.5 * tree_->getResolution();
    const double d = std::max({lo - p(i), 0.0, p(i) - (lo + edge)});
    squared += d * d;
  }
  return std::sqrt(squared);
}

LocalMap::TileIndex LocalMap::tileOf(const octomap::OcTreeKey& k) const {
  const unsigned shift = tree_->getTreeDepth() - tile_depth_;
  return {uint16_t(k[0] >> shift), uint16_t(k[1] >> shift), uint16_t(k[2] >> shift)};
}

std::string LocalMap::tilePath(const TileIndex& t) const {
  return (fs::path(directory_) /
          ("tile_" + std::to_string(tile_depth_) + "_" + std::to_string(t[0]) + "_" +
           std::to_string(t[1]) + "_" + std::to_string(t[2]) + ".ot"))
      .string();
}

InsertStats LocalMap::insertSemanticScan(const octomap::Pointcloud& points_W,
                                         const std::vector<float>& evidence,
                                         const octomap::point3d& origin_W) {
  follow(origin_W);
  return tree_->insertSemanticScan(points_W, evidence, origin_W);
}

void LocalMap::follow(const octomap::point3d& origin_W) {
  if (!std::isfinite(origin_W.x()) || !std::isfinite(origin_W.y()) || !std::isfinite(origin_W.z()))
    return;  // the insert refuses such an origin itself
  const std::string problem = radiusProblem(*tree_, radius_);  // max_range may have changed
  if (!problem.empty()) throw std::invalid_argument(problem);
  std::vector<TileIndex> leaving;
  for (auto it = tree_->begin_tree(tile_depth_), end = tree_->end_tree(); it != end; ++it) {
    if (it.getDepth() != tile_depth_) continue;  // (pruned blocks above a tile stay: one node)
    const TileIndex tile = tileOf(it.getKey());
    if (distanceToTile(origin_W, tile) > radius_ + tileEdge()) leaving.push_back(tile);
  }
  writeOut(leaving);
  readBack(origin_W);
}

void LocalMap::writeOut(const std::vector<TileIndex>& tiles) {
  if (tiles.empty()) return;
  cached_.clear();
  const unsigned shift = tree_->getTreeDepth() - tile_depth_;
  try {
    for (const TileIndex& tile : tiles) {
      const octomap::OcTreeKey key(octomap::key_type(tile[0] << shift),
                                   octomap::key_type(tile[1] << shift),
                                   octomap::key_type(tile[2] << shift));
      std::unique_ptr<EvidentialOcTree> part =
          detail::TreeEditing::detachSubtree(*tree_, key, tile_depth_);
      if (!part) continue;
      const std::string path = tilePath(tile);
      try {
        saveMap(*part, path);
      } catch (...) {
        tree_->merge(*part);  // a failed save (a full disk) puts the tile back: nothing is lost
        throw;
      }
      on_disk_[tile] = path;
      ++tiles_written_;
    }
  } catch (...) {
    detail::TreeEditing::updateInnerNodes(*tree_);
    throw;
  }
  detail::TreeEditing::updateInnerNodes(*tree_);
}

void LocalMap::readBack(const octomap::point3d& origin_W) {
  for (auto it = on_disk_.begin(); it != on_disk_.end();) {
    if (distanceToTile(origin_W, it->first) > radius_) {
      ++it;
      continue;
    }
    cached_.clear();
    tree_->merge(*loadMap(it->second));
    std::remove(it->second.c_str());
    it = on_disk_.erase(it);
    ++tiles_read_;
  }
}

std::vector<std::string> LocalMap::tileFiles() const {
  std::vector<std::string> files;
  for (const auto& tile : on_disk_) files.push_back(tile.second);
  return files;
}

void LocalMap::adoptTiles(const std::vector<std::string>& files) {
  std::map<TileIndex, std::string> adopted;
  const unsigned shift = tree_->getTreeDepth() - tile_depth_;
  for (const std::string& file : files) {
    unsigned depth = 0, x = 0, y = 0, z = 0;
    char end = 0;
    const std::string name = fs::path(file).filename().string();
    if (std::sscanf(name.c_str(), "tile_%u_%u_%u_%u.o%c", &depth, &x, &y, &z, &end) != 5 ||
        depth != tile_depth_ || x > 0xffff || y > 0xffff || z > 0xffff) {
      throw std::runtime_error(file + " is not a tile of this local map (tiles of depth " +
                               std::to_string(tile_depth_) + ": another resolution or radius?)");
    }
    const TileIndex tile{uint16_t(x), uint16_t(y), uint16_t(z)};
    const octomap::OcTreeKey key(octomap::key_type(x << shift), octomap::key_type(y << shift),
                                 octomap::key_type(z << shift));
    if (tree_->search(key, tile_depth_) != nullptr)  // the tile, or a pruned block over it
      throw std::runtime_error(file + ": the tree already holds this tile");
    adopted[tile] = file;
  }
  cached_.clear();
  for (const auto& [tile, file] : adopted) {
    const std::string path = tilePath(tile);
    linkOrCopyFile(file, path);
    on_disk_[tile] = path;
  }
}

std::unique_ptr<EvidentialOcTree> LocalMap::globalMap() const {
  auto global = std::make_unique<EvidentialOcTree>(*tree_);
  for (const auto& tile : on_disk_) global->merge(*loadMap(tile.second));
  return global;
}

const EvidentialOcTree& LocalMap::mapAt(const octomap::point3d& point_W) const {
  octomap::OcTreeKey key;
  if (!safeCoordToKey(*tree_, point_W, &key)) return *tree_;  // NaN, inf, off the map: unknown
  const TileIndex tile = tileOf(key);
  const auto file = on_disk_.find(tile);
  if (file == on_disk_.end()) return *tree_;
  for (const auto& [index, map] : cached_)
    if (index == tile) return *map;
  if (cached_.size() == kCachedTiles) cached_.erase(cached_.begin());
  std::unique_ptr<EvidentialOcTree> part = loadMap(file->second);
  detail::TreeEditing::readOutLike(*tree_, *part);  // a tile holds no evidence statistic
  cached_.emplace_back(tile, std::move(part));
  return *cached_.back().second;
}

}  // namespace evidential_octomap
