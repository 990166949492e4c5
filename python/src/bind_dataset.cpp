// The CLI's SemanticKITTI-layout reader and evidence sources, so Python maps exactly the points
// and evidence `evidential_octomap map` maps. Evidence derived from hard labels says so.
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bindings.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evidence/evidence_sources.h"

namespace evidential_octomap::python {

namespace {
using evidential_octomap::Dataset;
using evidential_octomap::Scan;

Array<double> matrixArray(const Eigen::Matrix4d& T) {
  std::vector<double> values(16);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) values[r * 4 + c] = T(r, c);
  return toNumpy(std::move(values), {4, 4});
}

nb::object classArray(const std::vector<int>& classes) {
  if (classes.empty()) return nb::none();
  return nb::cast(toNumpy(std::vector<int32_t>(classes.begin(), classes.end()), {classes.size()}));
}

Array<float> deriveEvidence(const Scan& scan, int num_classes, const std::string& source,
                            float magnitude, int knn_k, double knn_radius) {
  evidential_octomap::EvidenceOptions options;
  options.source = evidential_octomap::evidenceSourceFromName(source);
  options.magnitude = magnitude;
  options.knn_k = knn_k;
  options.knn_radius = knn_radius;
  std::vector<float> evidence;
  {
    nb::gil_scoped_release release;
    evidence = evidential_octomap::deriveEvidence(scan, 0, options, num_classes, nullptr);
  }
  return toNumpy(std::move(evidence), {scan.size(), size_t(num_classes)});
}
}  // namespace

void bindDataset(nb::module_& m) {
  nb::class_<Scan>(m, "Scan", "One scan of a Dataset (points in the sensor frame).")
      .def_ro("name", &Scan::name)
      .def_prop_ro(
          "points",
          [](const Scan& s) {
            std::vector<float> xyz;
            xyz.reserve(s.size() * 3);
            for (const auto& p : s.points_S) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
            return toNumpy(std::move(xyz), {s.size(), 3});
          },
          kShared, "(N, 3) float32, sensor frame.")
      .def_prop_ro(
          "remission",
          [](const Scan& s) { return toNumpy(std::vector<float>(s.remission), {s.remission.size()}); },
          kShared, "(N,) float32 the .bin's fourth column (intensity).")
      .def(
          "points_world", [](const Scan& s) { return cloudArray(s.pointsW()); },
          "(N, 3) float32 in the map frame, transformed exactly as the CLI does.")
      .def_prop_ro(
          "origin",
          [](const Scan& s) {
            const Eigen::Vector3d o = s.originW();
            return toNumpy(std::vector<double>{o.x(), o.y(), o.z()}, {3});
          },
          kShared, "(3,) sensor origin in the map frame.")
      .def_prop_ro(
          "pose", [](const Scan& s) { return matrixArray(s.T_W_S); }, kShared,
          "(4, 4) sensor-to-map transform T_W_S.")
      .def_prop_ro(
          "gt", [](const Scan& s) { return classArray(s.gt); }, kShared,
          "(N,) int32 ground-truth class, or None.")
      .def_prop_ro(
          "predicted", [](const Scan& s) { return classArray(s.predicted); }, kShared,
          "(N,) int32 predicted class, or None.")
      .def_prop_ro(
          "evidence",
          [](const Scan& s) -> nb::object {
            if (s.evidence.empty()) return nb::none();
            const size_t c = s.evidence.size() / s.size();
            return nb::cast(toNumpy(std::vector<float>(s.evidence), {s.size(), c}));
          },
          kShared, "(N, C) float32 evidence from evidence/ or alpha/ files, or None.")
      .def("__len__", &Scan::size);

  nb::class_<Dataset>(m, "Dataset",
                      "A SemanticKITTI-layout sequence (velodyne/, labels/, predictions/, "
                      "evidence/ or alpha/, poses.txt, calib.txt) or a single pose-less scan.")
      .def_static(
          "open",
          [](const std::string& path, const ClassTable& classes) {
            return Dataset::open(path, classes);  // logits/ probabilities/: default conversion
          },
          nb::arg("path"), nb::arg("classes"), nb::keep_alive<0, 2>(),
          "Raises RuntimeError naming the path when the layout is not recognised.")
      .def_prop_ro("path", &Dataset::path)
      .def_prop_ro("stems", &Dataset::stems)
      .def_prop_ro("has_labels", &Dataset::hasLabels)
      .def_prop_ro("has_predictions", &Dataset::hasPredictions)
      .def_prop_ro("has_evidence", &Dataset::hasEvidence)
      .def(
          "pose", [](const Dataset& d, size_t i) { return matrixArray(d.pose(i)); }, nb::arg("i"))
      .def(
          "load",
          [](const Dataset& d, size_t i) {
            if (i >= d.size()) {
              throw nb::index_error(
                  ("scan " + std::to_string(i) + " of " + std::to_string(d.size())).c_str());
            }
            nb::gil_scoped_release release;
            return d.load(i);
          },
          nb::arg("i"), "Loads scan i; raises RuntimeError naming a malformed file.")
      .def("__len__", &Dataset::size);

  const evidential_octomap::EvidenceOptions defaults;
  m.def("derive_evidence", &deriveEvidence, nb::arg("scan"), nb::arg("num_classes"),
        nb::arg("source") = evidential_octomap::evidenceSourceName(defaults.source),
        nb::arg("magnitude") = defaults.magnitude, nb::arg("knn_k") = defaults.knn_k,
        nb::arg("knn_radius") = defaults.knn_radius,
        "(N, C) evidence of a scan: 'file' (the dataset's evidence files), or derived from its "
        "hard predictions: 'onehot' or 'knn-vote' (see evidence_sources.h). 'confusion' needs "
        "other scans and is the CLI's.");
  m.def(
      "evidence_is_derived",
      [](const std::string& source) {
        return evidential_octomap::derivedFromHardLabels(evidential_octomap::evidenceSourceFromName(source));
      },
      nb::arg("source"), "Whether a source derives evidence from hard labels (label it so).");
}

}  // namespace evidential_octomap::python
