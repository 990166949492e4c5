// Per-point conversions of the core, so Python turns network outputs into evidence with the same
// code as the ROS node (src/ros/conversions.cpp calls the same functions): logits and class
// probabilities (subjective_logic.h), and the learned evidence head (learned_evidence.h).
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <string>

#include "bindings.h"
#include "evidential_octomap/evidence/learned_evidence.h"
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

}  // namespace

void bindConversions(nb::module_& m) {
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
