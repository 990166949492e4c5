// LocalMap: a map whose memory stays bounded, tiles on disk (evidential_octomap/local_map.h).
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>

#include "bindings.h"
#include "evidential_octomap/local_map.h"

namespace evidential_octomap::python {

void bindLocalMap(nb::module_& m) {
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
            return query(local.tree(), points, &local);
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

}  // namespace evidential_octomap::python
