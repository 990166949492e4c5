#include "evidential_octomap/tiled_map.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "evidential_octomap/io.h"
#include "evidential_octomap/safe_key.h"

namespace evidential_octomap {

namespace fs = std::filesystem;

namespace {
constexpr int kManifestFormat = 1;
}  // namespace

std::string tileFileName(unsigned depth, const TileIndex& t) {
  return "tile_" + std::to_string(depth) + "_" + std::to_string(t[0]) + "_" +
         std::to_string(t[1]) + "_" + std::to_string(t[2]) + ".ot";
}

bool parseTileFileName(const std::string& path, unsigned* depth, TileIndex* tile) {
  unsigned d = 0, x = 0, y = 0, z = 0;
  char end = 0;
  const std::string name = fs::path(path).filename().string();
  if (std::sscanf(name.c_str(), "tile_%u_%u_%u_%u.o%c", &d, &x, &y, &z, &end) != 5 ||
      end != 't' || tileFileName(d, {uint16_t(x), uint16_t(y), uint16_t(z)}) != name ||
      x > 0xffff || y > 0xffff || z > 0xffff) {
    return false;
  }
  *depth = d;
  *tile = {uint16_t(x), uint16_t(y), uint16_t(z)};
  return true;
}

// --- manifest ---------------------------------------------------------------------------------

void writeTiledMapManifest(const std::string& directory, const TiledMapManifest& m) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // the statistic and resolution read back bit for bit
  out << YAML::BeginMap << YAML::Key << "format" << YAML::Value << kManifestFormat;
  out << YAML::Key << "resolution" << YAML::Value << m.resolution;
  out << YAML::Key << "tile_depth" << YAML::Value << m.tile_depth;
  out << YAML::Key << "rule" << YAML::Value << m.rule;
  out << YAML::Key << "classes" << YAML::Value << YAML::Flow << m.class_names;
  out << YAML::Key << "evidence_log_sum" << YAML::Value << m.evidence_log_sum;
  out << YAML::Key << "evidence_points" << YAML::Value << m.evidence_points;
  out << YAML::Key << "tiles" << YAML::Value << YAML::BeginSeq;
  for (const TileIndex& t : m.tiles) out << YAML::Flow << std::vector<unsigned>{t[0], t[1], t[2]};
  out << YAML::EndSeq << YAML::EndMap;
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) throw std::runtime_error("cannot make " + directory + ": " + ec.message());
  writeFileAtomically((fs::path(directory) / TiledMapManifest::kFileName).string(),
                      std::string(out.c_str()) + "\n");
}

TiledMapManifest readTiledMapManifest(const std::string& directory) {
  const std::string path = (fs::path(directory) / TiledMapManifest::kFileName).string();
  if (!fs::is_regular_file(path))
    throw std::runtime_error(directory + " is not a tiled map (no " + TiledMapManifest::kFileName +
                             ")");
  TiledMapManifest m;
  try {
    const YAML::Node root = YAML::LoadFile(path);
    if (root["format"].as<int>() != kManifestFormat)
      throw std::runtime_error("unsupported format " + root["format"].as<std::string>());
    m.resolution = root["resolution"].as<double>();
    m.tile_depth = root["tile_depth"].as<unsigned>();
    m.rule = root["rule"].as<std::string>();
    m.class_names = root["classes"].as<std::vector<std::string>>();
    m.evidence_log_sum = root["evidence_log_sum"].as<double>();
    m.evidence_points = root["evidence_points"].as<uint64_t>();
    for (const YAML::Node& t : root["tiles"]) {
      const auto v = t.as<std::vector<unsigned>>();
      if (v.size() != 3 || std::max({v[0], v[1], v[2]}) > 0xffff)
        throw std::runtime_error("a tile is not three keys");
      m.tiles.push_back({uint16_t(v[0]), uint16_t(v[1]), uint16_t(v[2])});
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  if (!(m.resolution > 0.0) || m.tile_depth < 1 || m.tile_depth > 16 || m.class_names.empty())
    throw std::runtime_error(path + ": resolution, tile_depth (1..16) or classes out of range");
  return m;
}

// --- splitting a map into tiles -------------------------------------------------------------

namespace {
// Expands the pruned blocks above `depth`, so that every voxel lies in a node at `depth`.
void splitAbove(EvidentialOcTree& tree, EvidentialOcTreeNode* node, unsigned d, unsigned depth) {
  if (d >= depth) return;
  if (!tree.nodeHasChildren(node)) tree.expandNode(node);
  for (unsigned i = 0; i < 8; ++i)
    if (tree.nodeChildExists(node, i)) splitAbove(tree, tree.getNodeChild(node, i), d + 1, depth);
}
}  // namespace

unsigned TiledMap::tileDepthForEdge(double resolution, double edge) {
  unsigned depth = 16;
  while (depth > 1 && resolution * double(1u << (16 - depth + 1)) <= edge) --depth;
  return depth;
}

WrittenTiles TiledMap::writeTiles(EvidentialOcTree& tree, unsigned depth,
                                  const std::string& directory) {
  if (depth < 1 || depth > tree.getTreeDepth())
    throw std::invalid_argument("tile depth " + std::to_string(depth) + " outside 1.." +
                                std::to_string(tree.getTreeDepth()));
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) throw std::runtime_error("cannot make " + directory + ": " + ec.message());
  WrittenTiles written;
  written.evidence_log_sum = tree.evidence_log_sum_;
  written.evidence_points = tree.evidence_points_;
  if (!tree.root) return written;
  splitAbove(tree, tree.root, 0, depth);
  std::vector<octomap::OcTreeKey> keys;
  for (auto it = tree.begin_tree(depth), end = tree.end_tree(); it != end; ++it)
    if (it.getDepth() == depth) keys.push_back(it.getKey());
  const unsigned shift = tree.getTreeDepth() - depth;
  for (const octomap::OcTreeKey& key : keys) {
    std::unique_ptr<EvidentialOcTree> part = tree.detachSubtree(key, depth);
    const TileIndex tile{uint16_t(key[0] >> shift), uint16_t(key[1] >> shift),
                         uint16_t(key[2] >> shift)};
    saveMap(*part, (fs::path(directory) / tileFileName(depth, tile)).string());
    written.tiles.push_back(tile);
  }
  tree.updateInnerNodes();
  return written;
}

// --- reading ----------------------------------------------------------------------------------

TiledMap::TiledMap(const std::string& directory)
    : directory_(directory), manifest_(readTiledMapManifest(directory)) {
  sorted_ = manifest_.tiles;
  std::sort(sorted_.begin(), sorted_.end());
  for (const TileIndex& t : sorted_)
    if (!fs::is_regular_file(tilePath(t)))
      throw std::runtime_error(directory + ": tile " + tileFileName(manifest_.tile_depth, t) +
                               " of its manifest is missing");
}

double TiledMap::tileEdge() const {
  return manifest_.resolution * double(1u << (16 - manifest_.tile_depth));
}

TileIndex TiledMap::tileOf(const octomap::OcTreeKey& k) const {
  const unsigned shift = 16 - manifest_.tile_depth;
  return {uint16_t(k[0] >> shift), uint16_t(k[1] >> shift), uint16_t(k[2] >> shift)};
}

std::string TiledMap::tilePath(const TileIndex& tile) const {
  return (fs::path(directory_) / tileFileName(manifest_.tile_depth, tile)).string();
}

bool TiledMap::hasTile(const TileIndex& tile) const {
  return std::binary_search(sorted_.begin(), sorted_.end(), tile);
}

std::unique_ptr<EvidentialOcTree> TiledMap::readTile(const TileIndex& t) const {
  const std::string path = tilePath(t);
  std::unique_ptr<EvidentialOcTree> tile = loadMap(path);
  const TiledMapManifest& m = manifest_;
  if (std::fabs(tile->getResolution() - m.resolution) > 1e-9 * m.resolution ||
      tile->classNames() != m.class_names || tile->config().rule != m.rule)
    throw std::runtime_error(path + " is a tile of another map (resolution, classes or rule)");
  ++tiles_loaded_;
  return tile;
}

std::unique_ptr<EvidentialOcTree> TiledMap::loadTile(const TileIndex& tile) const {
  std::unique_ptr<EvidentialOcTree> map = readTile(tile);
  map->evidence_log_sum_ = manifest_.evidence_log_sum;
  map->evidence_points_ = manifest_.evidence_points;
  map->followEvidenceStatistic();
  return map;
}

const EvidentialOcTree& TiledMap::emptyMap() const {
  if (!empty_) {
    if (manifest_.tiles.empty()) {
      SemanticConfig config;
      config.rule = manifest_.rule;
      empty_ = std::make_unique<EvidentialOcTree>(
          manifest_.resolution, int(manifest_.class_names.size()), config);
    } else {
      empty_ = loadTile(manifest_.tiles.front())->emptyLike();
    }
    empty_->evidence_log_sum_ = manifest_.evidence_log_sum;
    empty_->evidence_points_ = manifest_.evidence_points;
    empty_->followEvidenceStatistic();
  }
  return *empty_;
}

std::unique_ptr<EvidentialOcTree> TiledMap::region(const octomap::point3d& lo,
                                                   const octomap::point3d& hi) const {
  auto map = std::make_unique<EvidentialOcTree>(emptyMap());
  const unsigned shift = 16 - manifest_.tile_depth;
  for (const TileIndex& t : manifest_.tiles) {
    bool touches = true;
    for (int i = 0; i < 3; ++i) {
      const double first = (double(unsigned(t[i]) << shift) - 32768.0) * manifest_.resolution;
      touches = touches && first <= hi(i) && first + tileEdge() >= lo(i);
    }
    if (!touches) continue;
    map->merge(*readTile(t));
  }
  // merge() summed the tiles' statistics (none): the whole map's reads out as the whole map.
  map->evidence_log_sum_ = manifest_.evidence_log_sum;
  map->evidence_points_ = manifest_.evidence_points;
  map->followEvidenceStatistic();
  return map;
}

std::unique_ptr<EvidentialOcTree> TiledMap::globalMap() const {
  const double far = 1e9;
  return region(octomap::point3d(-far, -far, -far), octomap::point3d(far, far, far));
}

const EvidentialOcTree& TiledMap::mapAt(const octomap::point3d& point_W) const {
  emptyMap();
  octomap::OcTreeKey key;
  if (!safeCoordToKey(*empty_, point_W, &key)) return *empty_;
  const TileIndex tile = tileOf(key);
  if (!hasTile(tile)) return *empty_;
  for (const auto& [index, map] : cached_)
    if (index == tile) return *map;
  if (cached_.size() == kCachedTiles) cached_.erase(cached_.begin());
  std::unique_ptr<EvidentialOcTree> map;
  if (empty_->config().semantic_occupied_only) {
    // A voxel without evidence answers from its neighbours within a query's support, which
    // may lie in the next tiles.
    const std::array<int, 3> reach = empty_->querySupportReach();
    const double margin = (std::max({reach[0], reach[1], reach[2]}) + 1) * manifest_.resolution;
    const unsigned shift = 16 - manifest_.tile_depth;
    octomap::point3d lo, hi;
    for (int i = 0; i < 3; ++i) {
      lo(i) = float((double(unsigned(tile[i]) << shift) - 32768.0) * manifest_.resolution - margin);
      hi(i) = float(lo(i) + tileEdge() + 2.0 * margin);
    }
    map = region(lo, hi);
  } else {
    map = loadTile(tile);
  }
  cached_.emplace_back(tile, std::move(map));
  return *cached_.back().second;
}

}  // namespace evidential_octomap
