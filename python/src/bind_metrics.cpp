// The CLI's metrics (core metrics.h) on numpy queries: one metric set for the map and for the
// input, on the same queries.
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bindings.h"
#include "evidential_octomap/evaluation/metrics.h"

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

void checkLength(size_t expected, size_t got, const char* what) {
  if (got != expected) {
    throw std::invalid_argument(std::string(what) + " has " + std::to_string(got) +
                                " rows, expected one per query (" + std::to_string(expected) + ")");
  }
}

std::vector<Query> makeQueries(const std::optional<PointsIn>& points, const LabelsIn& gt,
                               const std::optional<LabelsIn>& predicted) {
  const size_t n = gt.shape(0);
  if (points) checkLength(n, points->shape(0), "points");
  if (predicted) checkLength(n, predicted->shape(0), "predicted");
  std::vector<Query> queries(n);
  for (size_t i = 0; i < n; ++i) {
    queries[i].gt = gt.data()[i];
    if (predicted) queries[i].predicted = predicted->data()[i];
    if (points) {
      const auto p = points->view();
      queries[i].point_W = octomap::point3d(p(i, 0), p(i, 1), p(i, 2));
    }
  }
  return queries;
}

void bindResults(nb::module_& m) {
  nb::class_<ErrorDetection>(m, "ErrorDetection",
                             "How well one uncertainty output flags wrong labels.")
      .def_ro("output", &ErrorDetection::output,
              "'u', 'conflict', '1-max_p', 'dissonance' or 'error_probability' (the "
              "calibration's error model where the map has one, else 1-max_p).")
      .def_ro("auroc", &ErrorDetection::auroc)
      .def_ro("aurc", &ErrorDetection::aurc)
      .def_ro("error_rate_by_decile", &ErrorDetection::error_rate_by_decile)
      .def_ro("mean_output_by_decile", &ErrorDetection::mean_output_by_decile);
  nb::class_<ReliabilityBin>(m, "ReliabilityBin", "One confidence bin of the ECE.")
      .def_ro("lower", &ReliabilityBin::lower)
      .def_ro("upper", &ReliabilityBin::upper)
      .def_ro("count", &ReliabilityBin::count)
      .def_ro("mean_confidence", &ReliabilityBin::mean_confidence)
      .def_ro("accuracy", &ReliabilityBin::accuracy);
  nb::class_<QualityMetrics>(m, "QualityMetrics",
                             "One row's metrics on the queries (definitions in metrics.h).")
      .def_ro("queries", &QualityMetrics::queries)
      .def_ro("labelled", &QualityMetrics::labelled, "Queries with a label.")
      .def_ro("miou_all", &QualityMetrics::miou_all, "Over every query, no label = wrong.")
      .def_ro("acc_all", &QualityMetrics::acc_all)
      .def_ro("miou_labelled", &QualityMetrics::miou_labelled, "Over labelled queries.")
      .def_ro("acc_labelled", &QualityMetrics::acc_labelled)
      .def_ro("brier", &QualityMetrics::brier, "Multi-class Brier score, every query.")
      .def_ro("nll", &QualityMetrics::nll)
      .def_ro("ece", &QualityMetrics::ece)
      .def_ro("error_rate_labelled", &QualityMetrics::error_rate_labelled)
      .def_ro("reliability", &QualityMetrics::reliability)
      .def_prop_ro(
          "error_detection",
          [](const QualityMetrics& q) {
            nb::dict out;
            for (const ErrorDetection& d : q.error_detection) out[d.output.c_str()] = nb::cast(d);
            return out;
          },
          "{output: ErrorDetection} for 'the label is wrong' among labelled queries.")
      .def_prop_ro(
          "iou_all", [](const QualityMetrics& r) { return iouArray(r.all); }, kShared,
          "(C,) IoU per class over every query (NaN: class absent).")
      .def_prop_ro(
          "confusion_all", [](const QualityMetrics& r) { return confusionArray(r.all); },
          kShared, "(C, C + 1) every query, rows GT, last column 'no label'.")
      .def_prop_ro(
          "confusion_labelled",
          [](const QualityMetrics& r) { return confusionArray(r.labelled_only); }, kShared);
  nb::class_<MapMetrics>(m, "MapMetrics", "A map's metrics at GT-labelled points.")
      .def_ro("quality", &MapMetrics::quality)
      .def_ro("occupied", &MapMetrics::occupied, "Queries whose voxel is occupied.")
      .def_ro("occupancy_coverage", &MapMetrics::occupancy_coverage)
      .def_ro("semantic_coverage", &MapMetrics::semantic_coverage,
              "Queries whose voxel holds evidence (the paper's O.Acc).");
}
}  // namespace

void bindMetrics(nb::module_& m) {
  bindResults(m);
  m.def(
      "evaluate_map",
      [](const EvidentialOcTree& tree, const PointsIn& points, const LabelsIn& gt,
         int ignore_class) {
        const std::vector<Query> queries = makeQueries(points, gt, std::nullopt);
        nb::gil_scoped_release release;
        return evaluateMap(tree, queries, ignore_class);
      },
      nb::arg("tree"), nb::arg("points"), nb::arg("gt"), nb::arg("ignore_class") = -1,
      "Metrics of the map at GT-labelled points (map frame), as `evidential_octomap eval`.");
  m.def(
      "evaluate_input",
      [](const LabelsIn& gt, std::optional<LabelsIn> predicted, std::optional<MatrixIn> evidence,
         int num_classes, int ignore_class) {
        const std::vector<Query> queries = makeQueries(std::nullopt, gt, predicted);
        std::vector<float> values;
        if (evidence) {
          checkLength(queries.size(), evidence->shape(0), "evidence");
          if (evidence->shape(1) != size_t(num_classes)) {
            throw std::invalid_argument("evidence must have num_classes columns");
          }
          values.assign(evidence->data(), evidence->data() + evidence->size());
        } else if (!predicted) {
          throw std::invalid_argument("give the input's predicted classes or its evidence");
        }
        nb::gil_scoped_release release;
        return evaluateInput(queries, values, num_classes, ignore_class);
      },
      nb::arg("gt"), nb::arg("predicted") = nb::none(), nb::arg("evidence") = nb::none(),
      nb::arg("num_classes"), nb::arg("ignore_class") = -1,
      "The input's per-point metrics on the same queries: from its evidence (N, C) when given, "
      "else from its hard predictions.");
}

}  // namespace evidential_octomap::python
