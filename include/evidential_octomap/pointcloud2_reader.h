// The reader of sensor_msgs/PointCloud2 clouds with per-point semantics, without ROS: the
// message's layout (fields, strides, byte order, data) in, points and N x C evidence out, by one
// set of field rules for every way a cloud comes in (the ROS 1 node, the ROS 2 node and the bag
// mapper through the Python package).
#pragma once

#include <octomap/Pointcloud.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap {

// sensor_msgs/PointField's datatypes, with its numbers.
enum CloudDatatype : uint8_t {
  kInt8 = 1, kUint8 = 2, kInt16 = 3, kUint16 = 4, kInt32 = 5, kUint32 = 6, kFloat32 = 7,
  kFloat64 = 8,
};

struct CloudField {
  std::string name;
  uint32_t offset = 0;
  uint8_t datatype = 0;  // CloudDatatype
  uint32_t count = 1;
};

// A PointCloud2 as it is laid out; `data` is not owned.
struct CloudLayout {
  std::vector<CloudField> fields;
  uint32_t height = 0, width = 0, point_step = 0, row_step = 0;
  bool is_bigendian = false;
  const uint8_t* data = nullptr;
  size_t size = 0;  // bytes of data
};

// Which per-point field carries the semantics.
enum class EvidenceInput {
  kAuto,      // the first present of: evidence, alpha, logits, probabilities, label
  kEvidence,  // `evidence` (float32, count = C) or `evidence_0` .. `evidence_{C-1}`
  kAlpha,     // `alpha` (float32, count = C) or `alpha_0` ..; e = alpha - 1
  kLogits,    // `logits` (float32, count = C) or `logits_0` ..; e by CloudReadOptions::logits
  kProbabilities,  // `probabilities` (count = C) or `probabilities_0` ..: confidence-scaled
  kLabel,     // `label` (any integer or float type): one-hot evidence of `label_magnitude`
  kNone,      // no semantics: occupancy only (zero evidence)
};
// "auto", "evidence", "alpha", "logits", "probabilities", "label", "none"; throws
// std::invalid_argument otherwise.
EvidenceInput evidenceInputFromName(const std::string& name);

struct CloudReadOptions {
  int num_classes = 0;
  EvidenceInput input = EvidenceInput::kAuto;
  float label_magnitude = kEvidenceMagnitude;  // evidence of the labelled class for `label` inputs
  // `logits`: how they become evidence (subjective_logic.h); `probabilities` and softmax
  // logits: E of the confidence-scaled conversion.
  LogitTransform logit_transform = LogitTransform::kSoftmax;
  float probability_magnitude = kEvidenceMagnitude;
  // Labels are raw dataset ids, mapped through this table's learning map (nullptr: class ids).
  const ClassTable* raw_label_table = nullptr;
  // kAuto and no semantic field: the points without evidence (for a model to give it), rather
  // than an error.
  bool semantics_optional = false;
};

// A cloud read from a message: points in the message's frame and their N x C evidence.
struct SemanticCloud {
  octomap::Pointcloud points_S;
  std::vector<float> evidence;  // row-major, points_S.size() x C; empty without semantics
  size_t nonfinite_points = 0;  // dropped for NaN/inf coordinates (organised clouds)
  std::string source;           // which field was read, e.g. "evidence[20]", "label", "none"
};

// Reads x, y, z and the evidence by field name and offset, for any point_step, row_step,
// height and byte order. Returns "" on success, else a message saying what is wrong (missing
// field, wrong count or type, truncated data, NaN/inf/negative evidence, label out of range);
// `out` is then unspecified. Points with coordinates beyond float range (NaN, inf) are dropped
// and counted.
std::string readPointCloud2(const CloudLayout& cloud, const CloudReadOptions& options,
                            SemanticCloud* out);

}  // namespace evidential_octomap
