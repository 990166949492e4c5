// The CLI's metrics (core metrics.h) on numpy queries: map metrics and the input's per-point ones.
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>

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
  nb::class_<QualityMetrics>(m, "QualityMetrics",
                             "One row's metrics on the queries (metrics.h): the map's or the "
                             "input's answers.")
      .def_ro("queries", &QualityMetrics::queries)
      .def_ro("labelled", &QualityMetrics::labelled, "Queries with an answer (a label).")
      .def_ro("miou_all", &QualityMetrics::miou_all, "Over every query, no label = wrong.")
      .def_ro("acc_all", &QualityMetrics::acc_all)
      .def_ro("miou_labelled", &QualityMetrics::miou_labelled)
      .def_ro("acc_labelled", &QualityMetrics::acc_labelled)
      .def_ro("brier", &QualityMetrics::brier, "Multi-class Brier score over every query.")
      .def_ro("nll", &QualityMetrics::nll)
      .def_ro("ece", &QualityMetrics::ece)
      .def_ro("error_rate_labelled", &QualityMetrics::error_rate_labelled)
      .def_prop_ro(
          "error_detection",
          [](const QualityMetrics& q) {
            nb::dict out;
            for (const ErrorDetection& d : q.error_detection) {
              out[d.output.c_str()] = nb::make_tuple(d.auroc, d.aurc);
            }
            return out;
          },
          "{output: (AUROC, AURC)} for 'the label is wrong' among labelled queries.")
      .def_prop_ro(
          "iou_all", [](const QualityMetrics& q) { return iouArray(q.all); }, kShared,
          "(C,) IoU per class over every query (NaN: class absent).")
      .def_prop_ro(
          "confusion_all", [](const QualityMetrics& q) { return confusionArray(q.all); },
          kShared, "(C, C + 1) every query, rows GT, last column 'no label'.")
      .def_prop_ro(
          "confusion_labelled",
          [](const QualityMetrics& q) { return confusionArray(q.labelled_only); }, kShared);
  nb::class_<MapMetrics>(m, "MapMetrics", "Map metrics of DESIGN section 6 (metrics.h).")
      .def_ro("quality", &MapMetrics::quality)
      .def_ro("occupied", &MapMetrics::occupied, "Queries whose voxel is occupied.")
      .def_ro("occupancy_coverage", &MapMetrics::occupancy_coverage)
      .def_ro("semantic_coverage", &MapMetrics::semantic_coverage,
              "Queries whose voxel holds evidence (the paper's O.Acc).");

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
      [](const LabelsIn& gt, const LabelsIn& predicted, int num_classes, int ignore_class,
         std::optional<MatrixIn> evidence) {
        if (gt.shape(0) != predicted.shape(0)) {
          throw std::invalid_argument("gt and predicted must have the same length");
        }
        std::vector<Query> queries(gt.shape(0));
        for (size_t i = 0; i < queries.size(); ++i) {
          queries[i].gt = gt.data()[i];
          queries[i].predicted = predicted.data()[i];
        }
        std::vector<float> e;
        if (evidence) {
          if (evidence->shape(0) != queries.size() || int(evidence->shape(1)) != num_classes) {
            throw std::invalid_argument("evidence must be (N, num_classes)");
          }
          e.assign(evidence->data(), evidence->data() + evidence->size());
        }
        return evaluateInput(queries, e, num_classes, ignore_class);
      },
      nb::arg("gt"), nb::arg("predicted"), nb::arg("num_classes"), nb::arg("ignore_class") = -1,
      nb::arg("evidence") = nb::none(),
      "The input's per-point metrics on the same queries: each point's evidence (N, C) when "
      "given, else its hard prediction.");
}

}  // namespace evidential_octomap::python
