// `evidential_octomap tiles DIR [--query X,Y,Z]... [--export map.ot]`: a tiled map (the batch
// mapper's output, tiled_map.h): what it holds, answers at points (reading only their tiles),
// and the whole map as one .ot, streamed tile by tile.
#include <iostream>
#include <memory>

#include "commands.h"
#include "evidential_octomap/tiled_map.h"

namespace evidential_octomap::tools {

namespace {
struct TilesOptions {
  std::string directory;
  std::vector<std::vector<double>> queries;
  std::string output;
};

void printInfo(const TiledMap& tiled) {
  const TiledMapManifest& m = tiled.manifest();
  std::cout << "tiled map:       " << tiled.directory() << "\n"
            << "resolution:      " << m.resolution << " m\n"
            << "tiles:           " << m.tiles.size() << " of depth " << m.tile_depth << " ("
            << tiled.tileEdge() << " m edge)\n"
            << "classes (C):     " << m.class_names.size() << "\n"
            << "rule:            " << m.rule << "\n";
}

void printAnswer(const TiledMap& tiled, const std::vector<double>& xyz) {
  const octomap::point3d p{float(xyz[0]), float(xyz[1]), float(xyz[2])};
  const EvidentialOcTree& map = tiled.mapAt(p);
  const EvidentialOcTreeNode* node = map.nodeAt(p);
  const VoxelOpinion o = map.query(p);
  std::cout << "(" << xyz[0] << ", " << xyz[1] << ", " << xyz[2] << "): "
            << (node == nullptr ? "unknown" : map.isNodeOccupied(node) ? "occupied" : "free")
            << ", label " << (o.label >= 0 ? tiled.manifest().class_names[o.label] : "none")
            << ", uncertainty " << o.uncertainty << "\n";
}

void runTiles(const TilesOptions& o) {
  const TiledMap tiled(o.directory);
  printInfo(tiled);
  for (const auto& xyz : o.queries) printAnswer(tiled, xyz);
  if (!o.queries.empty()) std::cout << "tiles read:      " << tiled.tilesLoaded() << "\n";
  if (!o.output.empty()) {
    tiled.writeGlobalMap(o.output);
    std::cout << "wrote " << o.output << " (the whole map, streamed tile by tile)\n";
  }
}
}  // namespace

void addTilesCommand(CLI::App& app) {
  auto o = std::make_shared<TilesOptions>();
  CLI::App* cmd = app.add_subcommand(
      "tiles", "A tiled map (python -m evidential_octomap.batch): its tiles, answers at points "
               "(reading only the tiles they touch) and the whole map as one .ot");
  cmd->add_option("directory", o->directory, "Tiled map directory (holds tiled_map.yaml)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("-q,--query", o->queries, "A point X,Y,Z [m] to answer (repeatable)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("-e,--export", o->output,
                  "Write the whole map as one .ot, one tile in memory at a time");
  cmd->callback([o]() { runTiles(*o); });
}

}  // namespace evidential_octomap::tools
