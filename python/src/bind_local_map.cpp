// LocalMap: a map whose memory stays bounded, tiles on disk (evidential_octomap/local_map.h);
// TiledMap: a map stored as tiles (evidential_octomap/tiled_map.h).
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include "bindings.h"
#include "evidential_octomap/local_map.h"
#include "evidential_octomap/tiled_map.h"

namespace evidential_octomap::python {

namespace {
void bindTiledMap(nb::module_& m);
}  // namespace

void bindLocalMap(nb::module_& m) {
  bindTiledMap(m);
  nb::class_<LocalMap>(m, "LocalMap",
                       "Keeps the map within `radius` of the sensor in `tree` and moves the rest "
                       "to `tile_directory` as .ot tiles, read back when the sensor returns; "
                       "global_map() is the whole map, equal to the one built without tiles.")
      .def(nb::init<EvidentialOcTree*, const std::string&, double>(), nb::arg("tree"),
           nb::arg("tile_directory"), nb::arg("radius"), nb::keep_alive<1, 2>(),
           "radius [m] >= LocalMap.reach(tree) (the tree's max_range must be finite); the "
           "directory is created and must hold no tiles.")
      .def(
          "insert_scan",
          [](LocalMap& local, const PointsIn& points, const MatrixIn& evidence,
             std::optional<std::array<double, 3>> origin, std::optional<PoseIn> pose) {
            if (pose) {
              const auto T = pose->view();
              local.follow(octomap::point3d(T(0, 3), T(1, 3), T(2, 3)));
            } else if (origin) {
              local.follow(octomap::point3d((*origin)[0], (*origin)[1], (*origin)[2]));
            }
            return insertScan(local.tree(), points, evidence, origin, pose, nullptr);
          },
          nb::arg("points"), nb::arg("evidence"), nb::kw_only(), nb::arg("origin") = nb::none(),
          nb::arg("pose") = nb::none(),
          "Writes out and reads back tiles for the sensor's position, then "
          "tree.insert_scan(points, evidence, origin=..., pose=...) on the resident map.")
      .def(
          "follow",
          [](LocalMap& local, const std::array<double, 3>& origin) {
            local.follow(octomap::point3d(origin[0], origin[1], origin[2]));
          },
          nb::arg("origin"), "Writes out and reads back tiles for a sensor at origin (3,).")
      .def(
          "query",
          [](const LocalMap& local, const PointsIn& points) {
            return query(local.tree(), points,
                         [&](const octomap::point3d& p) -> const EvidentialOcTree& {
                           return local.mapAt(p);
                         });
          },
          nb::arg("points"),
          "tree.query(points), but points on tiles on disk are answered from their tile (read "
          "from its file; the last 4 tiles read stay in memory), as the whole map would.")
      .def("global_map", &LocalMap::globalMap,
           "The whole map: the tree merged with every tile (a new EvidentialOcTree).")
      .def_static("reach", &LocalMap::reach, nb::arg("tree"),
                  "How far [m] one scan can change the map (max_range, kernel support, a voxel "
                  "diagonal); < 0 for an unlimited max_range.")
      .def_prop_ro("radius", &LocalMap::radius)
      .def_prop_ro("tile_edge", &LocalMap::tileEdge, "Edge of one tile [m].")
      .def_prop_ro("tiles_on_disk", &LocalMap::tilesOnDisk)
      .def_prop_ro("tiles_written", &LocalMap::tilesWritten)
      .def_prop_ro("tiles_read", &LocalMap::tilesRead);
}

namespace {
using Tile = std::tuple<unsigned, unsigned, unsigned>;
Tile toTuple(const TileIndex& t) { return {t[0], t[1], t[2]}; }
TileIndex toIndex(const Tile& t) {
  const auto [x, y, z] = t;
  if (std::max({x, y, z}) > 0xffff) throw std::invalid_argument("tile keys are 0..65535");
  return {uint16_t(x), uint16_t(y), uint16_t(z)};
}
std::vector<Tile> toTuples(const std::vector<TileIndex>& tiles) {
  std::vector<Tile> out;
  for (const TileIndex& t : tiles) out.push_back(toTuple(t));
  return out;
}

void bindTiledMap(nb::module_& m) {
  m.def(
      "write_tiles",
      [](EvidentialOcTree& tree, unsigned tile_depth, const std::string& directory) {
        const WrittenTiles w = TiledMap::writeTiles(tree, tile_depth, directory);
        return std::make_tuple(toTuples(w.tiles), w.evidence_log_sum, w.evidence_points);
      },
      nb::arg("tree"), nb::arg("tile_depth"), nb::arg("directory"),
      "Moves every node of `tree` at tile_depth into directory/tile_<depth>_<x>_<y>_<z>.ot (tree "
      "is empty afterwards). Returns (tiles, evidence_log_sum, evidence_points): the tiles "
      "written and the map's adaptive-cap statistic.");
  m.def(
      "write_tiled_map_manifest",
      [](const std::string& directory, double resolution, unsigned tile_depth,
         const std::vector<std::string>& class_names, const std::string& rule,
         double evidence_log_sum, uint64_t evidence_points, const std::vector<Tile>& tiles) {
        TiledMapManifest manifest{resolution, tile_depth, class_names, rule,
                                  evidence_log_sum, evidence_points, {}};
        for (const Tile& t : tiles) manifest.tiles.push_back(toIndex(t));
        writeTiledMapManifest(directory, manifest);
      },
      nb::arg("directory"), nb::arg("resolution"), nb::arg("tile_depth"), nb::arg("class_names"),
      nb::arg("rule"), nb::arg("evidence_log_sum"), nb::arg("evidence_points"), nb::arg("tiles"),
      "Writes directory/tiled_map.yaml (atomically).");
  m.def("tile_depth_for_edge", &TiledMap::tileDepthForEdge, nb::arg("resolution"),
        nb::arg("edge"), "The tile depth whose tile edge is the largest at most edge [m].");
  m.def("tile_file_name",
        [](unsigned depth, const Tile& tile) { return tileFileName(depth, toIndex(tile)); },
        nb::arg("depth"), nb::arg("tile"), "tile_<depth>_<x>_<y>_<z>.ot");

  nb::class_<TiledMap>(m, "TiledMap",
                       "A map stored as tiles (a directory with tiled_map.yaml, written by "
                       "evidential_octomap.batch): queries read only the tiles they touch.")
      .def(nb::init<const std::string&>(), nb::arg("directory"))
      .def(
          "query",
          [](const TiledMap& tiled, const PointsIn& points) {
            return query(tiled.emptyMap(), points,
                         [&](const octomap::point3d& p) -> const EvidentialOcTree& {
                           return tiled.mapAt(p);
                         });
          },
          nb::arg("points"),
          "EvidentialOcTree.query(points) as the whole map answers, each point from its tile "
          "(read from its file; the last 4 stay in memory).")
      .def(
          "region",
          [](const TiledMap& tiled, const std::array<double, 3>& lo,
             const std::array<double, 3>& hi) {
            return tiled.region(octomap::point3d(lo[0], lo[1], lo[2]),
                                octomap::point3d(hi[0], hi[1], hi[2]));
          },
          nb::arg("min"), nb::arg("max"), "The tiles that intersect the box, merged into one map.")
      .def(
          "load_tile", [](const TiledMap& tiled, const Tile& t) { return tiled.loadTile(toIndex(t)); },
          nb::arg("tile"), "One tile as a map.")
      .def("global_map", &TiledMap::globalMap, "The whole map in memory.")
      .def("write_global_map", &TiledMap::writeGlobalMap, nb::arg("path"),
           "The whole map as one .ot, streamed tile by tile (one tile in memory at a time); "
           "the same bytes as global_map().save(path).")
      .def_prop_ro("tiles", [](const TiledMap& t) { return toTuples(t.manifest().tiles); })
      .def_prop_ro("tile_depth", [](const TiledMap& t) { return t.manifest().tile_depth; })
      .def_prop_ro("resolution", [](const TiledMap& t) { return t.manifest().resolution; })
      .def_prop_ro("class_names", [](const TiledMap& t) { return t.manifest().class_names; })
      .def_prop_ro("tile_edge", &TiledMap::tileEdge, "Edge of one tile [m].")
      .def_prop_ro("tiles_loaded", &TiledMap::tilesLoaded, "Tile files read so far.");
}
}  // namespace

}  // namespace evidential_octomap::python
