// The CLI's metrics (core metrics.h) on numpy queries: map metrics and the input's per-point ones.
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include "bindings.h"
#include "evidential_octomap/metrics.h"

namespace evidential_octomap::python {

namespace {
// (C, C + 1) counts, rows = GT, columns = predicted, last column = "no label".
Array<uint64_t> confusionArray(const ConfusionMatrix& matrix) {
  const int c = matrix.numClasses();
  std::vector<uint64_t> counts;
  counts.reserve(size_t(c) * (c + 1));
  for (int gt = 0; gt < c; ++gt) {
    for (int p = 0; p < c; ++p) counts.push_back(matrix.at(gt, p));
    counts.push_back(matrix.at(gt, -1));
  }
  return toNumpy(std::move(counts), {size_t(c), size_t(c) + 1});
}

Array<double> iouArray(const ConfusionMatrix& matrix) {
  std::vector<double> iou(matrix.numClasses());
  for (int c = 0; c < matrix.numClasses(); ++c) iou[c] = matrix.iou(c);
  return toNumpy(std::move(iou), {iou.size()});
}

std::vector<Query> makeQueries(const PointsIn& points, const LabelsIn& gt,
                               const std::optional<LabelsIn>& predicted) {
  const size_t n = points.shape(0);
  if (gt.shape(0) != n || (predicted && predicted->shape(0) != n)) {
    throw std::invalid_argument("points, gt and predicted must have the same length");
  }
  std::vector<Query> queries(n);
  const auto p = points.view();
  for (size_t i = 0; i < n; ++i) {
    queries[i] = {octomap::point3d(p(i, 0), p(i, 1), p(i, 2)), gt.data()[i],
                  predicted ? predicted->data()[i] : -1};
  }
  return queries;
}
}  // namespace

void bindMetrics(nb::module_& m) {
  nb::class_<MapMetrics>(m, "MapMetrics", "Map metrics of DESIGN section 6 (metrics.h).")
      .def_ro("queries", &MapMetrics::queries)
      .def_ro("covered", &MapMetrics::covered, "Queries whose voxel is occupied.")
      .def_ro("occupied_accuracy", &MapMetrics::occupied_accuracy, "O.Acc = covered / queries.")
      .def_ro("miou", &MapMetrics::miou, "Over covered queries.")
      .def_ro("accuracy", &MapMetrics::accuracy, "Over covered queries.")
      .def_ro("miou_all", &MapMetrics::miou_all, "Over every query, uncovered = wrong.")
      .def_ro("accuracy_all", &MapMetrics::accuracy_all)
      .def_ro("brier", &MapMetrics::brier)
      .def_ro("mean_u_correct", &MapMetrics::mean_u_correct)
      .def_ro("mean_u_wrong", &MapMetrics::mean_u_wrong)
      .def_prop_ro("uncertainty_scale", [](const MapMetrics& r) { return r.scale.describe(); })
      .def_prop_ro(
          "iou", [](const MapMetrics& r) { return iouArray(r.confusion); }, kShared,
          "(C,) IoU per class over covered queries (NaN: class absent).")
      .def_prop_ro(
          "confusion", [](const MapMetrics& r) { return confusionArray(r.confusion); }, kShared,
          "(C, C + 1) covered queries, rows GT, last column 'no label'.")
      .def_prop_ro(
          "confusion_all", [](const MapMetrics& r) { return confusionArray(r.confusion_all); },
          kShared);
  nb::class_<PredictionMetrics>(m, "PredictionMetrics", "The input's per-point metrics.")
      .def_ro("queries", &PredictionMetrics::queries)
      .def_ro("miou", &PredictionMetrics::miou)
      .def_ro("accuracy", &PredictionMetrics::accuracy)
      .def_prop_ro(
          "iou", [](const PredictionMetrics& r) { return iouArray(r.confusion); }, kShared)
      .def_prop_ro(
          "confusion", [](const PredictionMetrics& r) { return confusionArray(r.confusion); },
          kShared);

  m.def(
      "evaluate_map",
      [](const EvidentialOcTree& tree, const PointsIn& points, const LabelsIn& gt,
         std::optional<LabelsIn> predicted, int ignore_class) {
        std::vector<Query> queries = makeQueries(points, gt, predicted);
        nb::gil_scoped_release release;
        return evaluateMap(tree, queries, ignore_class);
      },
      nb::arg("tree"), nb::arg("points"), nb::arg("gt"), nb::arg("predicted") = nb::none(),
      nb::arg("ignore_class") = -1,
      "Metrics of the map at GT-labelled points (map frame), as `evidential_octomap eval`.");
  m.def(
      "evaluate_predictions",
      [](const LabelsIn& gt, const LabelsIn& predicted, int num_classes, int ignore_class) {
        if (gt.shape(0) != predicted.shape(0)) {
          throw std::invalid_argument("gt and predicted must have the same length");
        }
        std::vector<Query> queries(gt.shape(0));
        for (size_t i = 0; i < queries.size(); ++i) {
          queries[i].gt = gt.data()[i];
          queries[i].predicted = predicted.data()[i];
        }
        return evaluatePredictions(queries, num_classes, ignore_class);
      },
      nb::arg("gt"), nb::arg("predicted"), nb::arg("num_classes"), nb::arg("ignore_class") = -1,
      "The input predictions' per-point metrics on the same queries.");
}

}  // namespace evidential_octomap::python
