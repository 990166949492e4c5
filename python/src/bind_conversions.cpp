// Per-point conversions of the core, so Python turns clouds and network outputs into evidence
// with the same code as the ROS 1 node: PointCloud2 clouds (pointcloud2_reader.h), logits and
// class probabilities (subjective_logic.h), and the learned evidence head (learned_evidence.h).
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <string>
#include <tuple>

#include "bindings.h"
#include "evidential_octomap/evidence/learned_evidence.h"
#include "evidential_octomap/pointcloud2_reader.h"
#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap::python {

namespace {

using FloatsIn = nb::ndarray<const float, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

// Applies `convert(row_in, row_out)` ("" or what is wrong) to every row; the first bad row
// raises ValueError "point i: ...".
template <typename Convert>
Array<float> convertRows(const MatrixIn& values, Convert convert) {
  const size_t n = values.shape(0), c = values.shape(1);
  std::vector<float> out(n * c);
  std::string error;
  size_t bad = 0;
  {
    nb::gil_scoped_release release;
    for (size_t i = 0; i < n && error.empty(); ++i) {
      error = convert(values.data() + i * c, out.data() + i * c);
      bad = i;
    }
  }
  if (!error.empty()) throw std::invalid_argument("point " + std::to_string(bad) + ": " + error);
  return toNumpy(std::move(out), {n, c});
}

using BytesIn = nb::ndarray<const uint8_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using FieldIn = std::tuple<std::string, uint32_t, uint8_t, uint32_t>;

// (points (N, 3) float32, evidence (N, C) float32 or None, source, non-finite points dropped);
// ValueError with the reader's message for a cloud it refuses.
nb::tuple readCloud(const std::vector<FieldIn>& fields, const BytesIn& data, uint32_t height,
                    uint32_t width, uint32_t point_step, uint32_t row_step, bool is_bigendian,
                    int num_classes, const std::string& input, float label_magnitude,
                    const std::string& logit_transform, float probability_magnitude,
                    const ClassTable* raw_label_table) {
  CloudLayout layout;
  for (const auto& [name, offset, datatype, count] : fields)
    layout.fields.push_back({name, offset, datatype, count});
  layout.height = height;
  layout.width = width;
  layout.point_step = point_step;
  layout.row_step = row_step;
  layout.is_bigendian = is_bigendian;
  layout.data = data.data();
  layout.size = data.shape(0);
  CloudReadOptions options;
  options.num_classes = num_classes;
  options.input = evidenceInputFromName(input);
  options.label_magnitude = label_magnitude;
  options.logit_transform = logitTransformFromName(logit_transform);
  options.probability_magnitude = probability_magnitude;
  options.raw_label_table = raw_label_table;
  options.semantics_optional = true;  // a model may give the evidence
  SemanticCloud cloud;
  std::string error;
  {
    nb::gil_scoped_release release;
    error = readPointCloud2(layout, options, &cloud);
  }
  if (!error.empty()) throw std::invalid_argument(error);
  const size_t n = cloud.points_S.size();
  nb::object evidence = nb::none();
  if (!cloud.evidence.empty())
    evidence = nb::cast(toNumpy(std::move(cloud.evidence), {n, size_t(num_classes)}));
  return nb::make_tuple(cloudArray(cloud.points_S), evidence, cloud.source,
                        cloud.nonfinite_points);
}

}  // namespace

void bindConversions(nb::module_& m) {
  m.def("read_pointcloud2", &readCloud, nb::arg("fields"), nb::arg("data"), nb::arg("height"),
        nb::arg("width"), nb::arg("point_step"), nb::arg("row_step"), nb::arg("is_bigendian"),
        nb::arg("num_classes"), nb::arg("input") = "auto",
        nb::arg("label_magnitude") = kEvidenceMagnitude, nb::arg("logit_transform") = "softmax",
        nb::arg("probability_magnitude") = kEvidenceMagnitude,
        nb::arg("raw_label_table").none() = nb::none(),
        "A sensor_msgs/PointCloud2's points and evidence by the ROS 1 node's field rules (the "
        "same reader): fields as (name, offset, datatype, count), data as uint8. Returns (points "
        "(N, 3), evidence (N, C) or None without a semantic field, source, non-finite points "
        "dropped); raises ValueError saying what is wrong. pointcloud2.decode wraps it.");
  m.def(
      "evidence_from_logits",
      [](const MatrixIn& logits, const std::string& transform, float magnitude) {
        const LogitTransform t = logitTransformFromName(transform);
        const int c = int(logits.shape(1));
        return convertRows(logits, [&](const float* z, float* e) {
          return evidenceFromLogits(z, c, t, magnitude, e);
        });
      },
      nb::arg("logits"), nb::arg("transform") = "softmax", nb::arg("magnitude") = kEvidenceMagnitude,
      "(N, C) evidence of (N, C) logits: 'softmax' (then as evidence_from_probabilities), 'exp' "
      "or 'softplus' (EDL networks). Raises ValueError naming the first non-finite logit.");
  m.def(
      "evidence_from_probabilities",
      [](const MatrixIn& p, float magnitude) {
        const int c = int(p.shape(1));
        return convertRows(
            p, [&](const float* row, float* e) { return evidenceFromProbabilities(row, c, magnitude, e); });
      },
      nb::arg("probabilities"), nb::arg("magnitude") = kEvidenceMagnitude,
      "(N, C) confidence-scaled evidence e_c = E p_c (C p_max - 1) / (C - 1) of (N, C) class "
      "probabilities (normalised per row). Raises ValueError naming the first bad row.");

  nb::class_<LearnedEvidenceModel>(
      m, "LearnedEvidenceModel",
      "The learned evidence head (docs/learned_evidence.md): a small evidential MLP on a scan's "
      "geometry and a network's hard predictions, cross-fitted (a scan's evidence comes only "
      "from model folds not trained on it).")
      .def_static(
          "load", [](const std::string& path) { return LearnedEvidenceModel::load(path); },
          nb::arg("path"), "Raises RuntimeError naming the file and what is wrong.")
      .def_prop_ro("num_classes", &LearnedEvidenceModel::numClasses)
      .def_prop_ro("path", &LearnedEvidenceModel::path)
      .def_prop_ro("description", &LearnedEvidenceModel::description)
      .def(
          "evidence",
          [](const LearnedEvidenceModel& model, const PointsIn& xyz,
             std::optional<FloatsIn> remission, const LabelsIn& predicted) {
            const size_t n = xyz.shape(0);
            if (predicted.shape(0) != n || (remission && remission->shape(0) != n)) {
              throw std::invalid_argument("xyz, remission and predicted need one row per point (" +
                                          std::to_string(n) + ")");
            }
            std::vector<float> e;
            {
              nb::gil_scoped_release release;
              const ScanInput scan{xyz.data(), remission ? remission->data() : nullptr,
                                   reinterpret_cast<const int*>(predicted.data()), n};
              e = model.evidence(scan);
            }
            return toNumpy(std::move(e), {n, size_t(model.numClasses())});
          },
          nb::arg("xyz"), nb::arg("remission").none(), nb::arg("predicted"),
          "(N, C) evidence of one scan: xyz (N, 3) in the sensor frame, remission (N,) or None, "
          "the network's hard predictions (N,) int32 (-1: none). Raises RuntimeError when every "
          "fold was trained on this scan.");
}

}  // namespace evidential_octomap::python
