// EvidentialOcTree with numpy in and out: insert a scan, query points, export leaves, files,
// merge, ColorOcTree export. The GIL is released while C++ works on whole arrays.
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "bindings.h"
#include "evidential_octomap/calibration_file.h"
#include "evidential_octomap/detail/leaf_walk.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/projected_grid.h"
#include "evidential_octomap/safe_key.h"

namespace evidential_octomap::python {

namespace {

// Every leaf of the map (pruned blocks are one leaf of their own size).
struct Leaves {
  Array<float> centers;      // (M, 3)
  Array<float> sizes;        // (M,) edge length [m]
  Array<float> occupancy;    // (M,) probability
  Array<int32_t> labels;     // (M,)
  Array<float> uncertainty;  // (M,)
  Array<float> conflict;     // (M,)
  Array<float> error_probability;  // (M,) 1 - max_c p_c
  Array<float> belief;       // (M, C)
};

void checkRows(const MatrixIn& evidence, size_t points, int num_classes) {
  if (evidence.shape(0) != points || evidence.shape(1) != size_t(num_classes)) {
    throw std::invalid_argument("evidence has shape (" + std::to_string(evidence.shape(0)) + ", " +
                                std::to_string(evidence.shape(1)) + "), expected (" +
                                std::to_string(points) + ", " + std::to_string(num_classes) +
                                ") = (points, classes)");
  }
}

Leaves leaves(const EvidentialOcTree& tree, bool occupied_only, bool opinions) {
  const size_t num_classes = size_t(tree.numClasses());
  std::vector<float> centers, sizes, occupancy, uncertainty, conflict, error_probability, belief;
  std::vector<int32_t> labels;
  {
    nb::gil_scoped_release release;
    std::vector<const EvidentialOcTreeNode*> nodes;
    // Occupied leaves only: a free inner node has none below it (a view's walk skips most of
    // the map's free space).
    auto descend = [&](const EvidentialOcTreeNode& node, const octomap::OcTreeKey&, unsigned) {
      return !occupied_only || tree.isNodeOccupied(node);
    };
    auto visit = [&](const EvidentialOcTreeNode& leaf, const octomap::OcTreeKey& corner,
                     unsigned depth) {
      if (occupied_only && !tree.isNodeOccupied(leaf)) return;
      for (int a = 0; a < 3; ++a) centers.push_back(float(tree.keyToCoord(corner[a], depth)));
      sizes.push_back(static_cast<float>(tree.getNodeSize(depth)));
      occupancy.push_back(static_cast<float>(leaf.getOccupancy()));
      nodes.push_back(&leaf);
    };
    detail::walkLeaves(tree, descend, visit);
    if (opinions) {  // the read-out is most of the cost: in parallel, as query's
      const size_t m = nodes.size();
      labels.resize(m);
      uncertainty.resize(m);
      conflict.resize(m);
      error_probability.resize(m);
      belief.resize(m * num_classes);
#pragma omp parallel for schedule(static)
      for (size_t i = 0; i < m; ++i) {
        const VoxelOpinion o = tree.opinion(nodes[i]);
        labels[i] = o.label;
        uncertainty[i] = o.uncertainty;
        conflict[i] = o.conflict;
        error_probability[i] = tree.rule().errorProbability(o);
        std::copy(o.belief.begin(), o.belief.end(), belief.begin() + i * num_classes);
      }
    }
  }
  const size_t m = sizes.size(), with = opinions ? m : 0;
  return {toNumpy(std::move(centers), {m, 3}),
          toNumpy(std::move(sizes), {m}),
          toNumpy(std::move(occupancy), {m}),
          toNumpy(std::move(labels), {with}),
          toNumpy(std::move(uncertainty), {with}),
          toNumpy(std::move(conflict), {with}),
          toNumpy(std::move(error_probability), {with}),
          toNumpy(std::move(belief), {with, num_classes})};
}

// projected_map as (data (H, W) int8, origin (x, y), resolution); row j at y.
nb::tuple projectedMap(const EvidentialOcTree& tree, double min_z, double max_z) {
  ProjectedGrid grid;
  {
    nb::gil_scoped_release release;
    grid = projectOccupancy(tree, min_z, max_z);
  }
  const size_t height = grid.height, width = grid.width;
  return nb::make_tuple(toNumpy(std::move(grid.cells), {height, width}),
                        nb::make_tuple(grid.origin_x, grid.origin_y), grid.resolution);
}

nb::bytes toBytes(const EvidentialOcTree& tree) {
  std::ostringstream out;
  {
    nb::gil_scoped_release release;
    out << std::setprecision(17);  // AbstractOcTree::write prints the resolution as text
    if (!tree.write(out)) throw std::runtime_error("serialising the map failed");
  }
  const std::string data = out.str();
  return nb::bytes(data.data(), data.size());
}

std::unique_ptr<EvidentialOcTree> fromBytes(nb::bytes data) {
  std::istringstream in(std::string(data.c_str(), data.size()));
  nb::gil_scoped_release release;
  return loadMap(in, "<bytes>");
}

std::unique_ptr<EvidentialOcTree> makeTree(double resolution, const std::vector<std::string>& names,
                                           const std::optional<SemanticConfig>& config) {
  auto tree = std::make_unique<EvidentialOcTree>(resolution, static_cast<int>(names.size()),
                                                 config.value_or(SemanticConfig()));
  tree->setClassNames(names);
  return tree;
}

void bindResults(nb::module_& m) {
  nb::class_<QueryResult>(m, "QueryResult", "Per-point answers of EvidentialOcTree.query.")
      .def_ro("labels", &QueryResult::labels, kShared,
              "(N,) int32 argmax class, -1 without evidence.")
      .def_ro("belief", &QueryResult::belief, kShared,
              "(N, C) float32: dempster belief masses; sbki/ebs expected probabilities.")
      .def_ro("uncertainty", &QueryResult::uncertainty, kShared,
              "(N,) float32: the vacuity u, how little evidence the voxel holds (dempster mass u "
              "= C / S, 1 without evidence; sbki/ebs Dirichlet variance of the label). It does "
              "not say whether the label is right: use error_probability.")
      .def_ro("conflict", &QueryResult::conflict, kShared,
              "(N,) float32 in [0, 1): share of the fused evidence that disagreed "
              "(VoxelOpinion::conflict).")
      .def_ro("error_probability", &QueryResult::error_probability, kShared,
              "(N,) float32: the error probability, the map's probability that the label is "
              "wrong: the calibration's error model when one is applied (apply_calibration), "
              "else 1 - max_c p_c (dempster p = belief + u / C). Trust a label by it.")
      .def_ro("occupied", &QueryResult::occupied, kShared,
              "(N,) bool: the voxel is known and occupied.")
      .def_ro("known", &QueryResult::known, kShared, "(N,) bool: the voxel has been observed.");
  nb::class_<Leaves>(m, "Leaves", "Every leaf of a map as arrays (pruned blocks are one leaf).")
      .def_ro("centers", &Leaves::centers, kShared, "(M, 3) float32 centre [m].")
      .def_ro("sizes", &Leaves::sizes, kShared, "(M,) float32 edge length [m].")
      .def_ro("occupancy", &Leaves::occupancy, kShared, "(M,) float32 occupancy probability.")
      .def_ro("labels", &Leaves::labels, kShared, "(M,) int32 argmax class, -1 without evidence.")
      .def_ro("uncertainty", &Leaves::uncertainty, kShared,
              "(M,) float32: the vacuity u (as QueryResult's).")
      .def_ro("conflict", &Leaves::conflict, kShared, "(M,) float32.")
      .def_ro("error_probability", &Leaves::error_probability, kShared,
              "(M,) float32: the error probability, that the label is wrong (as QueryResult's).")
      .def_ro("belief", &Leaves::belief, kShared, "(M, C) float32.");
  nb::class_<InsertStats>(m, "InsertStats", "What one insert_scan did.")
      .def_ro("points_in", &InsertStats::points_in)
      .def_ro("points_skipped", &InsertStats::points_skipped,
              "Non-finite or outside the tree's key range.")
      .def_ro("points_beyond_range", &InsertStats::points_beyond_range)
      .def_ro("semantic_points", &InsertStats::semantic_points, "Left after down-sampling.")
      .def_ro("points_dropped_uncertain", &InsertStats::points_dropped_uncertain)
      .def_ro("uncertainty_threshold", &InsertStats::uncertainty_threshold)
      .def_ro("voxels_updated", &InsertStats::voxels_updated)
      .def_ro("ms_occupancy", &InsertStats::ms_occupancy)
      .def_ro("ms_kernel", &InsertStats::ms_kernel)
      .def_ro("ms_update", &InsertStats::ms_update);
}

void bindColorTree(nb::module_& m) {
  nb::class_<octomap::ColorOcTree>(m, "ColorOcTree",
                                   "OctoMap's ColorOcTree (opens in octovis and stock tools).")
      .def(
          "save",
          [](const octomap::ColorOcTree& tree, const std::string& path) {
            writeFileAtomically(path,
                                [&](std::ostream& out) { return tree.write(out) && out.good(); });
          },
          nb::arg("path"), "Writes an .ot file.")
      .def_prop_ro("num_leaves", &octomap::ColorOcTree::getNumLeafNodes)
      .def_prop_ro("resolution", &octomap::ColorOcTree::getResolution)
      .def(
          "colors",
          [](const octomap::ColorOcTree& tree, const PointsIn& points) {
            const size_t n = points.shape(0);
            std::vector<uint8_t> rgb(n * 3, 0);
            const auto p = points.view();
            for (size_t i = 0; i < n; ++i) {
              octomap::OcTreeKey key;
              if (!safeCoordToKey(tree, octomap::point3d(p(i, 0), p(i, 1), p(i, 2)), &key)) {
                continue;  // NaN, inf or beyond the map: unknown
              }
              const auto* node = tree.search(key);
              if (!node) continue;
              const auto c = node->getColor();
              rgb[i * 3] = c.r;
              rgb[i * 3 + 1] = c.g;
              rgb[i * 3 + 2] = c.b;
            }
            return toNumpy(std::move(rgb), {n, 3});
          },
          nb::arg("points"), "(N, 3) uint8 colour of each point's voxel (0 where unknown).");
}

}  // namespace

InsertStats insertScan(EvidentialOcTree& tree, const PointsIn& points, const MatrixIn& evidence,
                       std::optional<std::array<double, 3>> origin, std::optional<PoseIn> pose,
                       EvidentialOcTree* unobserved) {
  if (origin.has_value() == pose.has_value()) {
    throw std::invalid_argument(
        "give exactly one of origin (points in the map frame) or pose "
        "(4x4 sensor-to-map transform, points in the sensor frame)");
  }
  checkRows(evidence, points.shape(0), tree.numClasses());
  nb::gil_scoped_release release;
  std::vector<float> values(evidence.data(), evidence.data() + evidence.size());
  if (pose) {
    const auto T = pose->view();
    return tree.insertSemanticScan(toPointcloud(points, *pose), values,
                                   octomap::point3d(T(0, 3), T(1, 3), T(2, 3)), unobserved);
  }
  const std::array<double, 3>& o = *origin;
  return tree.insertSemanticScan(toPointcloud(points), values, octomap::point3d(o[0], o[1], o[2]),
                                 unobserved);
}

QueryResult query(const EvidentialOcTree& tree, const PointsIn& points, const MapAt& map_at) {
  const size_t n = points.shape(0);
  const int num_classes = tree.numClasses();
  std::vector<int32_t> labels(n);
  std::vector<float> belief(n * num_classes), uncertainty(n), conflict(n), error_probability(n);
  std::vector<uint8_t> occupied(n), known(n);
  const auto p = points.view();
  const auto answer = [&](size_t i, const EvidentialOcTree& map) {
    const octomap::point3d point(p(i, 0), p(i, 1), p(i, 2));
    const EvidentialOcTreeNode* node = map.nodeAt(point);  // NaN / far away: unknown
    const VoxelOpinion o = map.query(point);  // off the surface: the support answer
    labels[i] = o.label;
    uncertainty[i] = o.uncertainty;
    conflict[i] = o.conflict;
    error_probability[i] = map.rule().errorProbability(o);
    std::copy(o.belief.begin(), o.belief.end(), belief.begin() + i * num_classes);
    known[i] = node != nullptr;
    occupied[i] = node != nullptr && map.isNodeOccupied(node);
  };
  {
    nb::gil_scoped_release release;
    if (map_at) {  // one tile read at a time: mapAt is not thread-safe
      for (size_t i = 0; i < n; ++i) answer(i, map_at(octomap::point3d(p(i, 0), p(i, 1), p(i, 2))));
    } else {
#pragma omp parallel for schedule(static)
      for (size_t i = 0; i < n; ++i) answer(i, tree);
    }
  }
  return {
      toNumpy(std::move(labels), {n}),      toNumpy(std::move(belief), {n, size_t(num_classes)}),
      toNumpy(std::move(uncertainty), {n}), toNumpy(std::move(conflict), {n}),
      toNumpy(std::move(error_probability), {n}),
      toNumpyBool(std::move(occupied)),     toNumpyBool(std::move(known))};
}

void bindTree(nb::module_& m) {
  bindResults(m);
  bindColorTree(m);
  using Tree = EvidentialOcTree;
  nb::class_<Tree>(m, "EvidentialOcTree",
                   "An OctoMap occupancy tree whose voxels also fuse per-point semantic evidence.")
      .def(nb::new_([](double resolution, int classes, std::optional<SemanticConfig> config) {
             return std::make_unique<Tree>(resolution, classes, config.value_or(SemanticConfig()));
           }),
           nb::arg("resolution"), nb::arg("classes") = 1, nb::arg("config") = nb::none(),
           "classes: the number of classes C (names class_<i>).")
      .def(nb::new_([](double resolution, const std::vector<std::string>& classes,
                       std::optional<SemanticConfig> config) {
             return makeTree(resolution, classes, config);
           }),
           nb::arg("resolution"), nb::arg("classes"), nb::arg("config") = nb::none(),
           "classes: the class names.")
      .def(nb::new_([](double resolution, const ClassTable& classes,
                       std::optional<SemanticConfig> config) {
             auto tree = makeTree(resolution, classes.names, config);
             tree->setClasses(classes);
             return tree;
           }),
           nb::arg("resolution"), nb::arg("classes"), nb::arg("config") = nb::none(),
           "classes: a ClassTable (its names, ground and movable classes are used).")
      // --- settings
      .def_prop_ro("resolution", &Tree::getResolution)
      .def_prop_ro("num_classes", &Tree::numClasses)
      .def_prop_rw("class_names", &Tree::classNames, &Tree::setClassNames)
      .def_prop_rw("ground_classes", &Tree::groundClasses, &Tree::setGroundClasses,
                   "C flags (or none): classes whose points get ground_vertical_support.")
      .def_prop_rw("movable_classes", &Tree::movableClasses, &Tree::setMovableClasses,
                   "C flags (or none): classes that movable_clearing_observations clears.")
      .def_prop_ro(
          "config", [](const Tree& t) { return t.config(); }, "A copy of the mapping parameters.")
      .def("set_config", &Tree::setConfig, nb::arg("config"),
           "Replaces the parameters; a rule change is refused while the map holds evidence.")
      .def_prop_ro("rule", [](const Tree& t) { return t.rule().name(); })
      .def(
          "apply_calibration",
          [](Tree& t, const Calibration& calibration) { applyCalibration(calibration, &t); },
          nb::arg("calibration"),
           "Reads the map with a Calibration's cap and error model (error_probability becomes "
           "the model's); raises RuntimeError when it was fitted for other classes or rule.")
      .def_prop_ro(
          "calibrated", [](const Tree& t) { return t.errorModel() != nullptr; },
          "An error model is attached (apply_calibration).")
      .def_prop_ro("effective_evidence_cap", &Tree::effectiveEvidenceCap,
                   "The cap dempster opinions are read with now (the adaptive cap's value, or "
                   "the fixed one).")
      .def_prop_ro("mean_point_log_evidence", &Tree::meanPointLogEvidence,
                   "Mean over the inserted points of sum_c log1p(e^c / C): the adaptive cap's "
                   "statistic.")
      .def_prop_rw("prob_hit", &Tree::getProbHit, &Tree::setProbHit)
      .def_prop_rw("prob_miss", &Tree::getProbMiss, &Tree::setProbMiss)
      .def_prop_rw("clamping_thres_min", &Tree::getClampingThresMin, &Tree::setClampingThresMin)
      .def_prop_rw("clamping_thres_max", &Tree::getClampingThresMax, &Tree::setClampingThresMax)
      .def_prop_rw("occupancy_thres", &Tree::getOccupancyThres,
                   nb::overload_cast<double>(&Tree::setOccupancyThres))
      .def_prop_ro("clamping_thres_min_log", &Tree::getClampingThresMinLog)
      .def_prop_ro("clamping_thres_max_log", &Tree::getClampingThresMaxLog)
      .def("set_clamping_thres_log", &Tree::setClampingThresLog, nb::arg("min_log_odds"),
           nb::arg("max_log_odds"),
           "Clamping bounds in log-odds; (-3.4e38, 3.4e38) keeps log-odds unbounded (chunk maps "
           "merged later, then clamp_occupancy).")
      .def("clamp_occupancy", &Tree::clampOccupancy,
           "Clamps every node's log-odds to the current bounds.")
      // --- size
      .def_prop_ro("num_nodes", &Tree::size)
      .def_prop_ro("num_leaves", [](const Tree& t) { return t.getNumLeafNodes(); })
      .def_prop_ro("num_semantic_nodes", &Tree::numSemanticNodes)
      .def_prop_ro("memory_usage", &Tree::memoryUsage, "Bytes.")
      .def(
          "bounds",
          [](const Tree& t) {
            double x0, y0, z0, x1, y1, z1;
            t.getMetricMin(x0, y0, z0);
            t.getMetricMax(x1, y1, z1);
            return toNumpy(std::vector<double>{x0, y0, z0, x1, y1, z1}, {2, 3});
          },
          "(2, 3) min and max corner of the known space [m].")
      // --- integration and queries
      .def("insert_scan", &insertScan, nb::arg("points"), nb::arg("evidence"), nb::kw_only(),
           nb::arg("origin") = nb::none(), nb::arg("pose") = nb::none(),
           nb::arg("unobserved") = nb::none(),
           "Inserts one scan: points (N, 3) and evidence (N, C) >= 0. With origin (3,), points "
           "are in the map frame; with pose (4, 4) sensor-to-map, in the sensor frame. Raises "
           "ValueError, leaving the map unchanged, for malformed evidence. With unobserved (a map "
           "of "
           "equal resolution, C and rule), the evidence this map drops for voxels it has not "
           "observed yet is added there (for exact in-order merges, see add_evidence).")
      .def(
          "query",
          [](const EvidentialOcTree& tree, const PointsIn& points) { return query(tree, points); },
          nb::arg("points"),
          "Opinion and occupancy of each point's voxel: labels, error_probability (the "
          "probability that the label is wrong; trust a label by it), belief, uncertainty (the "
          "vacuity u), conflict, occupied, known.")
      .def("leaves", &leaves, nb::arg("occupied_only") = false, nb::arg("opinions") = true,
           "Every leaf as arrays; opinions=False: only centers, sizes and occupancy (the "
           "others have 0 rows), several times faster.")
      .def("projected_map", &projectedMap,
           nb::arg("min_z") = -std::numeric_limits<double>::infinity(),
           nb::arg("max_z") = std::numeric_limits<double>::infinity(),
           "octomap_server's projected_map: (data (H, W) int8, origin (x, y) of the grid's "
           "corner, resolution); a cell is 100 under an occupied leaf whose centre height is in "
           "[min_z, max_z], else 0 under such a free leaf, else -1. Row j lies at y. It spans "
           "the x-y extent of all leaves.")
      // --- files and maps
      .def(
          "save", [](const Tree& t, const std::string& path) { saveMap(t, path); }, nb::arg("path"),
          "Writes the .ot atomically; raises RuntimeError naming the problem.")
      .def(
          "save_occupancy",
          [](const Tree& t, const std::string& path) { saveBinaryOccupancy(t, path); },
          nb::arg("path"), "Occupancy-only OctoMap binary (.bt) for stock OctoMap tools.")
      .def_static(
          "load", [](const std::string& path) { return loadMap(path); }, nb::arg("path"),
          "Reads an .ot; raises RuntimeError for missing, foreign or corrupt files.")
      .def("to_bytes", &toBytes, "The .ot file's bytes.")
      .def_static("from_bytes", &fromBytes, nb::arg("data"), "Inverse of to_bytes.")
      .def(
          "merge",
          [](Tree& t, const Tree& other) {
            nb::gil_scoped_release release;
            t.merge(other);
          },
          nb::arg("other"),
          "Fuses a map of equal resolution, C and rule into this one (Dempster's rule in "
          "evidence space; occupancy log-odds add, clamped).")
      .def(
          "add_evidence",
          [](Tree& t, const Tree& evidence, Tree* rest) {
            nb::gil_scoped_release release;
            t.addEvidence(evidence, rest);
          },
          nb::arg("evidence"), nb::arg("rest") = nb::none(),
          "Adds the semantic evidence of `evidence` to the voxels this map has observed; that of "
          "other voxels goes to `rest` (or is dropped). For chunk maps of a sequence: "
          "earlier.add_evidence(later_unobserved, rest) then earlier.merge(later) equals the "
          "sequential map.")
      .def(
          "to_color_octree",
          [](const Tree& t, const ClassTable& classes, const std::string& mode) {
            return toColorOcTree(t, classes, colorModeFromName(mode));
          },
          nb::arg("classes"), nb::arg("mode") = "class",
          "ColorOcTree coloured by class ('class'), the error probability ('uncertainty': the "
          "probability that the label is wrong) or the vacuity u ('vacuity').")
      .def("copy", [](const Tree& t) { return std::make_unique<Tree>(t); })
      .def("__copy__", [](const Tree& t) { return std::make_unique<Tree>(t); })
      .def("clear", &Tree::clear)
      .def("__getstate__", &toBytes)
      .def("__setstate__",
           [](Tree& self, nb::bytes data) {
             std::unique_ptr<Tree> loaded = fromBytes(data);
             new (&self) Tree(*loaded);
           })
      .def("__repr__", [](const Tree& t) {
        return "EvidentialOcTree(resolution=" + std::to_string(t.getResolution()) +
               ", classes=" + std::to_string(t.numClasses()) + ", rule='" + t.rule().name() +
               "', leaves=" + std::to_string(t.getNumLeafNodes()) + ")";
      });
}

}  // namespace evidential_octomap::python
