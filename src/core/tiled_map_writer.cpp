// TiledMap::writeGlobalMap: the whole map as one .ot without the whole map in memory. An .ot's
// nodes are a depth-first stream, so the nodes above the tiles (inner nodes: their log-odds are
// the largest of their tiles', their child masks say which tiles exist) are written from a
// summary of every tile, and each tile's subtree is copied from its file in that order.
#include <algorithm>
#include <iomanip>
#include <stdexcept>

#include "evidential_octomap/io.h"
#include "evidential_octomap/tiled_map.h"
#include "log_odds_table.h"
#include "section_writer.h"

namespace evidential_octomap {

struct TiledMap::TileSummary {
  TileIndex tile;
  uint64_t order = 0;  // the tile's place in the depth-first stream
  float log_odds = 0.0f;
  bool leaf = false;  // a uniform block: the whole tile is one node
  uint64_t nodes = 0;
};

namespace {
// The child index of a tile's ancestor at `depth` below the root (OctoMap's computeChildIdx).
unsigned childAt(const TileIndex& t, unsigned tile_depth, unsigned depth) {
  const unsigned bit = tile_depth - 1 - depth;
  return ((t[0] >> bit) & 1u) | (((t[1] >> bit) & 1u) << 1) | (((t[2] >> bit) & 1u) << 2);
}

uint64_t streamOrder(const TileIndex& t, unsigned tile_depth) {
  uint64_t order = 0;
  for (unsigned d = 0; d < tile_depth; ++d) order = (order << 3) | childAt(t, tile_depth, d);
  return order;
}

// The node of `tile` in its own file's tree; throws when the file does not hold it.
const EvidentialOcTreeNode* tileNode(const EvidentialOcTree& map, const TileIndex& tile,
                                     unsigned tile_depth, const std::string& path) {
  const EvidentialOcTreeNode* node = map.getRoot();
  for (unsigned d = 0; node && d < tile_depth; ++d) {
    const unsigned i = childAt(tile, tile_depth, d);
    node = map.nodeHasChildren(node) && map.nodeChildExists(node, i) ? map.getNodeChild(node, i)
                                                                      : nullptr;
  }
  if (!node) throw std::runtime_error(path + " does not hold its tile's node");
  return node;
}
}  // namespace

std::vector<TiledMap::TileSummary> TiledMap::summarize(LogOddsTable& table) const {
  const unsigned depth = manifest_.tile_depth;
  std::vector<TileSummary> tiles;
  for (const TileIndex& t : manifest_.tiles) {
    const std::unique_ptr<EvidentialOcTree> map = readTile(t);
    const EvidentialOcTreeNode* node = tileNode(*map, t, depth, tilePath(t));
    TileSummary s{t, streamOrder(t, depth), node->getLogOdds(), !map->nodeHasChildren(node), 0};
    std::vector<const EvidentialOcTreeNode*> stack{node};
    while (!stack.empty()) {
      const EvidentialOcTreeNode* n = stack.back();
      stack.pop_back();
      ++s.nodes;
      table.add(n->getValue());
      if (!map->nodeHasChildren(n)) continue;
      for (unsigned i = 0; i < 8; ++i)
        if (map->nodeChildExists(n, i)) stack.push_back(map->getNodeChild(n, i));
    }
    tiles.push_back(s);
  }
  std::sort(tiles.begin(), tiles.end(),
            [](const TileSummary& a, const TileSummary& b) { return a.order < b.order; });
  for (size_t i = 1; i < tiles.size(); ++i)
    if (tiles[i].order == tiles[i - 1].order)
      throw std::runtime_error(directory_ + ": the manifest names a tile twice");
  return tiles;
}

uint64_t TiledMap::countNodes(std::vector<TileSummary>::const_iterator begin,
                              std::vector<TileSummary>::const_iterator end, unsigned depth) const {
  const unsigned tile_depth = manifest_.tile_depth;
  if (depth == tile_depth) return begin->nodes;
  uint64_t count = 1;
  for (auto group = begin; group != end;) {
    const unsigned child = childAt(group->tile, tile_depth, depth);
    auto next = std::find_if(group, end, [&](const TileSummary& s) {
      return childAt(s.tile, tile_depth, depth) != child;
    });
    count += countNodes(group, next, depth + 1);
    group = next;
  }
  return count;
}

void TiledMap::writeGlobalMap(const std::string& path) const {
  writeFileAtomically(path, [&](std::ostream& s) {
    LogOddsTable table;
    const std::vector<TileSummary> tiles = summarize(table);
    table.finish();
    const uint64_t nodes =
        tiles.empty() ? 0 : countNodes(tiles.begin(), tiles.end(), 0);
    // AbstractOcTree::write's text header, as saveMap writes it.
    s << std::setprecision(17) << "# Octomap OcTree file\n# (feel free to add / change comments, "
      << "but leave the first line as it is!)\n#\nid " << emptyMap().getTreeType()
      << "\nsize " << nodes << "\nres " << manifest_.resolution << "\ndata\n";
    EvidentialOcTree::SectionWriter out(s);
    emptyMap().writeHeader(out);
    out.pod(nodes);
    out.pod(static_cast<uint8_t>(table.width()));
    if (table.width() < 4) {
      out.pod(static_cast<uint32_t>(table.values().size()));
      for (float v : table.values()) out.pod(v);
    }
    if (!tiles.empty()) writeNodes(tiles.begin(), tiles.end(), 0, table, out);
    out.pod(kSectionEndMagic);
    const uint32_t crc = out.crc();
    s.write(reinterpret_cast<const char*>(&crc), sizeof(crc));
    return s.good();
  });
}

void TiledMap::writeNodes(std::vector<TileSummary>::const_iterator begin,
                          std::vector<TileSummary>::const_iterator end, unsigned depth,
                          const LogOddsTable& table, EvidentialOcTree::SectionWriter& out) const {
  const unsigned tile_depth = manifest_.tile_depth;
  if (depth == tile_depth) {
    const std::unique_ptr<EvidentialOcTree> map = readTile(begin->tile);
    const EvidentialOcTreeNode* node = tileNode(*map, begin->tile, tile_depth, "");
    if (!map->writeNodes(node, table, out))
      throw std::runtime_error(tilePath(begin->tile) + ": stale inner nodes");
    return;
  }
  // An inner node: the largest log-odds below it, and which children exist.
  float log_odds = begin->log_odds;
  uint8_t mask = 0;
  bool uniform = true;  // eight equal blocks might have been pruned into one
  for (auto it = begin; it != end; ++it) {
    log_odds = std::max(log_odds, it->log_odds);
    mask |= uint8_t(1u << childAt(it->tile, tile_depth, depth));
    uniform = uniform && it->leaf && it->log_odds == begin->log_odds;
  }
  if (depth + 1 == tile_depth && mask == 0xFF && uniform)
    throw std::runtime_error(directory_ + ": eight neighbouring tiles are uniform blocks, which "
                             "one map would prune into one node; not supported");
  switch (table.width()) {
    case 1: out.pod(static_cast<uint8_t>(table.code(log_odds))); break;
    case 2: out.pod(static_cast<uint16_t>(table.code(log_odds))); break;
    default: out.pod(log_odds);
  }
  out.pod(mask);
  for (auto group = begin; group != end;) {
    const unsigned child = childAt(group->tile, tile_depth, depth);
    auto next = std::find_if(group, end, [&](const TileSummary& s) {
      return childAt(s.tile, tile_depth, depth) != child;
    });
    writeNodes(group, next, depth + 1, table, out);
    group = next;
  }
}

}  // namespace evidential_octomap
