#include "evidential_octomap/pointcloud2_reader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace evidential_octomap {
namespace {

size_t typeSize(uint8_t datatype) {
  switch (datatype) {
    case kInt8:
    case kUint8: return 1;
    case kInt16:
    case kUint16: return 2;
    case kInt32:
    case kUint32:
    case kFloat32: return 4;
    case kFloat64: return 8;
    default: return 0;
  }
}

const char* typeName(uint8_t datatype) {
  static const char* names[] = {"?", "int8", "uint8", "int16", "uint16",
                                "int32", "uint32", "float32", "float64"};
  return datatype <= 8 ? names[datatype] : "?";
}

// One field as found in the message: where it is and how to read it.
struct FieldRef {
  uint32_t offset = 0;
  uint8_t datatype = 0;
  size_t size = 0;
};

// Reads one value of `datatype` at `p` as double, honouring the message's byte order.
// Whether a value read from the message stays finite as a float (a FLOAT64 field can hold
// 1e300, which is finite as a double and inf, or undefined behaviour, once cast).
bool fitsFloat(double v) { return std::fabs(v) <= std::numeric_limits<float>::max(); }

double readValue(const uint8_t* p, uint8_t datatype, bool swap) {
  uint8_t b[8];
  const size_t n = typeSize(datatype);
  if (swap) {
    for (size_t i = 0; i < n; ++i) b[i] = p[n - 1 - i];
  } else {
    std::memcpy(b, p, n);
  }
  switch (datatype) {
    case kInt8: { int8_t v; std::memcpy(&v, b, 1); return v; }
    case kUint8: return b[0];
    case kInt16: { int16_t v; std::memcpy(&v, b, 2); return v; }
    case kUint16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
    case kInt32: { int32_t v; std::memcpy(&v, b, 4); return v; }
    case kUint32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
    case kFloat32: { float v; std::memcpy(&v, b, 4); return v; }
    case kFloat64: { double v; std::memcpy(&v, b, 8); return v; }
    default: return std::nan("");
  }
}

const CloudField* findField(const CloudLayout& msg, const std::string& name) {
  for (const auto& f : msg.fields)
    if (f.name == name) return &f;
  return nullptr;
}

std::string fieldList(const CloudLayout& msg) {
  std::string s;
  for (const auto& f : msg.fields) s += (s.empty() ? "" : ", ") + f.name;
  return s.empty() ? "(none)" : s;
}

// Checks that `f` lies inside a point; "" or an error naming the field.
std::string checkField(const CloudField& f, uint32_t point_step) {
  const size_t n = typeSize(f.datatype);
  if (n == 0) return "field '" + f.name + "' has unknown datatype " + std::to_string(f.datatype);
  const size_t count = std::max<uint32_t>(f.count, 1);
  if (size_t(f.offset) + n * count > point_step)
    return "field '" + f.name + "' (offset " + std::to_string(f.offset) + ", " +
           std::to_string(count) + " x " + typeName(f.datatype) + ") does not fit point_step " +
           std::to_string(point_step);
  return "";
}

// Finds C float channels either as one field `base` with count C or as `base_0..base_{C-1}`.
// Returns "" and fills `refs` (C entries), "absent" when neither form exists, else an error.
std::string findChannels(const CloudLayout& msg, const std::string& base, int C,
                         std::vector<FieldRef>* refs) {
  refs->clear();
  auto isFloat = [](uint8_t t) { return t == kFloat32 || t == kFloat64; };
  if (const CloudField* f = findField(msg, base)) {
    if (!isFloat(f->datatype))
      return "field '" + base + "' must be float32 (or float64), is " + typeName(f->datatype);
    if (int(f->count) != C)
      return "field '" + base + "' has count " + std::to_string(f->count) + ", expected C = " +
             std::to_string(C) + " (num_classes)";
    std::string err = checkField(*f, msg.point_step);
    if (!err.empty()) return err;
    const size_t n = typeSize(f->datatype);
    for (int c = 0; c < C; ++c) refs->push_back({uint32_t(f->offset + c * n), f->datatype, n});
    return "";
  }
  if (!findField(msg, base + "_0")) return "absent";
  for (int c = 0; c < C; ++c) {
    const std::string name = base + "_" + std::to_string(c);
    const CloudField* f = findField(msg, name);
    if (!f)
      return "field '" + name + "' is missing: per-class fields need " + base + "_0 .. " + base +
             "_" + std::to_string(C - 1) + " (C = " + std::to_string(C) + ")";
    if (!isFloat(f->datatype))
      return "field '" + name + "' must be float32 (or float64), is " + typeName(f->datatype);
    std::string err = checkField(*f, msg.point_step);
    if (!err.empty()) return err;
    refs->push_back({f->offset, f->datatype, typeSize(f->datatype)});
  }
  if (findField(msg, base + "_" + std::to_string(C)))
    return "field '" + base + "_" + std::to_string(C) + "' exists: the cloud has more than C = " +
           std::to_string(C) + " (num_classes) channels";
  return "";
}

// "" when width, height, point_step, row_step and the data size describe a readable cloud.
std::string layoutProblem(const CloudLayout& msg) {
  if (size_t(msg.width) * msg.height == 0) return "cloud has zero points";
  if (msg.point_step == 0) return "point_step is 0";
  if (size_t(msg.row_step) < size_t(msg.width) * msg.point_step)
    return "row_step " + std::to_string(msg.row_step) + " < width " + std::to_string(msg.width) +
           " x point_step " + std::to_string(msg.point_step);
  const size_t needed =
      size_t(msg.row_step) * (msg.height - 1) + size_t(msg.width) * msg.point_step;
  if (msg.size < needed)
    return "truncated data: " + std::to_string(msg.size) + " bytes for " +
           std::to_string(msg.width) + " x " + std::to_string(msg.height) + " points need " +
           std::to_string(needed);
  return "";
}

// The x, y, z fields (float32 or float64, inside a point).
std::string findCoordinates(const CloudLayout& msg, FieldRef xyz[3]) {
  const char* axes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    const CloudField* f = findField(msg, axes[a]);
    if (!f) return std::string("missing field '") + axes[a] + "' (fields: " + fieldList(msg) + ")";
    if (f->datatype != kFloat32 && f->datatype != kFloat64)
      return std::string("field '") + axes[a] + "' must be float32 or float64, is " +
             typeName(f->datatype);
    std::string err = checkField(*f, msg.point_step);
    if (!err.empty()) return err;
    xyz[a] = {f->offset, f->datatype, typeSize(f->datatype)};
  }
  return "";
}

// Where a cloud's semantics are: the input kind found and its fields.
struct SemanticFields {
  EvidenceInput input = EvidenceInput::kNone;
  std::vector<FieldRef> channels;  // C of them for evidence, alpha, logits, probabilities
  FieldRef label;
};

const char* channelBase(EvidenceInput input) {
  switch (input) {
    case EvidenceInput::kEvidence: return "evidence";
    case EvidenceInput::kAlpha: return "alpha";
    case EvidenceInput::kLogits: return "logits";
    case EvidenceInput::kProbabilities: return "probabilities";
    default: return "";
  }
}

// Looks for one kind of input: "" (found, `fields` filled), "absent", or what is wrong.
std::string tryInput(const CloudLayout& msg, EvidenceInput kind, int C,
                     SemanticFields* fields) {
  if (kind != EvidenceInput::kLabel) {
    std::string err = findChannels(msg, channelBase(kind), C, &fields->channels);
    if (err.empty()) fields->input = kind;
    return err;
  }
  const CloudField* f = findField(msg, "label");
  if (!f) return "absent";
  std::string err = checkField(*f, msg.point_step);
  if (!err.empty()) return err;
  fields->label = {f->offset, f->datatype, typeSize(f->datatype)};
  fields->input = EvidenceInput::kLabel;
  return "";
}

// What to say when the field an input type asks for is not in the cloud.
std::string missingInput(const CloudLayout& msg, EvidenceInput input, int C) {
  const std::string fields = " (fields: " + fieldList(msg) + ")";
  const std::string count = std::to_string(C);
  switch (input) {
    case EvidenceInput::kAuto:
      return "no semantic field: expected 'evidence' (float32, count " + count +
             "), 'evidence_0'..'evidence_" + std::to_string(C - 1) +
             "', 'alpha', 'logits', 'probabilities' or 'label'" + fields;
    case EvidenceInput::kEvidence:
      return "missing field 'evidence' (float32, count " + count + ") or 'evidence_0'..'evidence_" +
             std::to_string(C - 1) + "'" + fields;
    case EvidenceInput::kLabel: return "missing field 'label'" + fields;
    default: {
      const std::string base = channelBase(input);
      return "missing field '" + base + "' (float32, count " + count + ") or '" + base + "_0'.." +
             fields;
    }
  }
}

// The semantic fields `options.input` asks for (auto: the first present of evidence, alpha,
// logits, probabilities, label); "" or what is missing or wrong.
std::string findSemantics(const CloudLayout& msg, EvidenceInput wanted, int C, bool optional,
                          SemanticFields* fields) {
  if (wanted == EvidenceInput::kNone) return "";
  std::string err = "absent";
  if (wanted == EvidenceInput::kAuto) {
    for (EvidenceInput kind : {EvidenceInput::kEvidence, EvidenceInput::kAlpha,
                               EvidenceInput::kLogits, EvidenceInput::kProbabilities,
                               EvidenceInput::kLabel}) {
      err = tryInput(msg, kind, C, fields);
      if (err != "absent") break;
    }
  } else {
    err = tryInput(msg, wanted, C, fields);
  }
  if (err != "absent") return err;
  return optional && wanted == EvidenceInput::kAuto ? "" : missingInput(msg, wanted, C);
}

std::string sourceName(EvidenceInput input, int C, const CloudReadOptions& options) {
  const std::string count = "[" + std::to_string(C) + "]";
  switch (input) {
    case EvidenceInput::kEvidence: return "evidence" + count;
    case EvidenceInput::kAlpha: return "alpha" + count;
    case EvidenceInput::kLogits:
      return "logits" + count + " (" + logitTransformName(options.logit_transform) + ")";
    case EvidenceInput::kProbabilities: return "probabilities" + count;
    case EvidenceInput::kLabel: return "label";
    default: return "none (occupancy only)";
  }
}

// One point's evidence or alpha channels into `row`; "" or what is wrong.
std::string readEvidenceChannels(const uint8_t* p, const SemanticFields& f, int C, bool swap,
                                 size_t index, std::vector<float>* row) {
  const bool alpha = f.input == EvidenceInput::kAlpha;
  for (int c = 0; c < C; ++c) {
    double value = readValue(p + f.channels[c].offset, f.channels[c].datatype, swap);
    if (alpha) value -= 1.0;
    if (!fitsFloat(value) || value < 0.0) {
      std::ostringstream s;
      s << "point " << index << ": " << (alpha ? "alpha" : "evidence") << " of class " << c
        << " is " << (alpha ? value + 1.0 : value)
        << (alpha ? " (alpha must be finite and >= 1, within float range)"
                  : " (evidence must be finite and >= 0, within float range)");
      return s.str();
    }
    (*row)[c] = static_cast<float>(value);
  }
  return "";
}

// One point's logits or probabilities, converted to evidence in `row`.
std::string readConvertedChannels(const uint8_t* p, const SemanticFields& f, int C, bool swap,
                                  const CloudReadOptions& options, size_t index,
                                  std::vector<float>* raw, std::vector<float>* row) {
  for (int c = 0; c < C; ++c)
    (*raw)[c] = float(readValue(p + f.channels[c].offset, f.channels[c].datatype, swap));
  const std::string bad =
      f.input == EvidenceInput::kLogits
          ? evidenceFromLogits(raw->data(), C, options.logit_transform,
                               options.probability_magnitude, row->data())
          : evidenceFromProbabilities(raw->data(), C, options.probability_magnitude, row->data());
  return bad.empty() ? "" : "point " + std::to_string(index) + ": " + bad;
}

// One point's label (a class id, or a raw id through the table) as one-hot evidence in `row`.
std::string readLabel(const uint8_t* p, const SemanticFields& f, int C, bool swap,
                      const CloudReadOptions& options, size_t index, std::vector<float>* row) {
  const double value = readValue(p + f.label.offset, f.label.datatype, swap);
  if (!std::isfinite(value) || value != std::floor(value) || value < 0) {
    std::ostringstream s;
    s << "point " << index << ": label " << value << " is not a non-negative integer";
    return s.str();
  }
  // Range-checked before any cast (a cast of 2^31, 4294967295 or 1e300 to int is undefined):
  // class ids lie in [0, C), raw ids in the 32-bit range the learning map is keyed by.
  const double limit = options.raw_label_table ? 4294967296.0 : double(C);
  if (value >= limit) {
    std::ostringstream s;
    s << std::setprecision(17) << "point " << index << ": label " << value
      << (options.raw_label_table ? " is beyond the 32-bit raw ids"
                                  : " is outside [0, " + std::to_string(C) + ")");
    return s.str();
  }
  int label = 0;
  if (options.raw_label_table) {
    try {
      label = options.raw_label_table->classOfRaw(static_cast<uint32_t>(value));
    } catch (const std::exception& e) {
      return "point " + std::to_string(index) + ": " + e.what();
    }
  } else {
    label = static_cast<int>(value);
  }
  if (label >= C) {
    std::ostringstream s;
    s << "point " << index << ": label " << label << " is outside [0, " << C << ")";
    return s.str();
  }
  evidenceFromLabel(label, C, options.label_magnitude, row->data());
  return "";
}

// One point's evidence row, from whichever fields the cloud has.
std::string readPointEvidence(const uint8_t* p, const SemanticFields& f, int C, bool swap,
                              const CloudReadOptions& options, size_t index,
                              std::vector<float>* scratch, std::vector<float>* row) {
  switch (f.input) {
    case EvidenceInput::kEvidence:
    case EvidenceInput::kAlpha: return readEvidenceChannels(p, f, C, swap, index, row);
    case EvidenceInput::kLogits:
    case EvidenceInput::kProbabilities:
      return readConvertedChannels(p, f, C, swap, options, index, scratch, row);
    case EvidenceInput::kLabel: return readLabel(p, f, C, swap, options, index, row);
    default: std::fill(row->begin(), row->end(), 0.f); return "";
  }
}

std::string noFinitePoints(size_t nonfinite) {
  return "cloud has no finite points (" + std::to_string(nonfinite) + " NaN/inf)";
}

// The common layout (x, y, z and a C-float `evidence` block, float32, host byte order) read with
// plain copies: 3 ms for 123k points and 20 classes, where the general per-value reader takes 20.
// Returns false, with `out` unspecified, when the layout is another or a value is not valid;
// the general reader then reads the cloud again and says what is wrong.
bool readPackedFloatCloud(const CloudLayout& msg, const FieldRef xyz[3],
                          const SemanticFields& fields, int C, SemanticCloud* out) {
  if (msg.is_bigendian || fields.input != EvidenceInput::kEvidence) return false;
  for (int a = 0; a < 3; ++a)
    if (xyz[a].datatype != kFloat32) return false;
  for (int c = 0; c < C; ++c)
    if (fields.channels[c].datatype != kFloat32 ||
        fields.channels[c].offset != fields.channels[0].offset + 4 * uint32_t(c))
      return false;
  const size_t n_points = size_t(msg.width) * msg.height;
  out->evidence.resize(n_points * C);
  float* evidence = out->evidence.data();
  size_t kept = 0;
  bool valid = true;  // every value finite, >= 0: NaN fails both comparisons
  for (uint32_t v = 0; v < msg.height; ++v) {
    const uint8_t* row_ptr = msg.data + size_t(v) * msg.row_step;
    for (uint32_t u = 0; u < msg.width; ++u) {
      const uint8_t* p = row_ptr + size_t(u) * msg.point_step;
      float q[3];
      for (int a = 0; a < 3; ++a) std::memcpy(&q[a], p + xyz[a].offset, 4);
      if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) {
        ++out->nonfinite_points;
        continue;
      }
      float* row = evidence + kept * C;
      std::memcpy(row, p + fields.channels[0].offset, 4 * size_t(C));
      for (int c = 0; c < C; ++c)
        valid &= row[c] >= 0.0f && row[c] <= std::numeric_limits<float>::max();
      out->points_S.push_back(q[0], q[1], q[2]);
      ++kept;
    }
  }
  out->evidence.resize(kept * C);
  return valid;
}

}  // namespace

EvidenceInput evidenceInputFromName(const std::string& name) {
  if (name == "auto") return EvidenceInput::kAuto;
  if (name == "evidence") return EvidenceInput::kEvidence;
  if (name == "alpha") return EvidenceInput::kAlpha;
  if (name == "logits") return EvidenceInput::kLogits;
  if (name == "probabilities") return EvidenceInput::kProbabilities;
  if (name == "label") return EvidenceInput::kLabel;
  if (name == "none") return EvidenceInput::kNone;
  throw std::invalid_argument("input_type '" + name +
                              "' is unknown; use auto, evidence, alpha, logits, probabilities, "
                              "label or none");
}

// Layout, coordinates, semantic fields, then every point (non-finite coordinates dropped).
std::string readPointCloud2(const CloudLayout& msg, const CloudReadOptions& options,
                            SemanticCloud* out) {
  const int C = options.num_classes;
  if (C <= 0) return "num_classes must be positive";
  out->points_S.clear();
  out->evidence.clear();
  out->nonfinite_points = 0;
  out->source.clear();
  FieldRef xyz[3];
  SemanticFields fields;
  std::string err = layoutProblem(msg);
  if (err.empty()) err = findCoordinates(msg, xyz);
  if (err.empty())
    err = findSemantics(msg, options.input, C, options.semantics_optional, &fields);
  if (!err.empty()) return err;
  // kAuto found no semantic field (semantics_optional): the points alone.
  const bool without_evidence =
      options.input == EvidenceInput::kAuto && fields.input == EvidenceInput::kNone;
  out->source = without_evidence ? "none" : sourceName(fields.input, C, options);

  const size_t n_points = size_t(msg.width) * msg.height;
  out->points_S.reserve(n_points);
  if (readPackedFloatCloud(msg, xyz, fields, C, out))
    return out->points_S.size() > 0 ? "" : noFinitePoints(out->nonfinite_points);
  out->points_S.clear();
  out->evidence.clear();
  out->nonfinite_points = 0;
  const bool swap = msg.is_bigendian != 0;  // this code assumes a little-endian host
  out->evidence.reserve(n_points * C);
  std::vector<float> row(C), scratch(C);
  for (uint32_t v = 0; v < msg.height; ++v) {
    const uint8_t* row_ptr = msg.data + size_t(v) * msg.row_step;
    for (uint32_t u = 0; u < msg.width; ++u) {
      const uint8_t* p = row_ptr + size_t(u) * msg.point_step;
      const double x = readValue(p + xyz[0].offset, xyz[0].datatype, swap);
      const double y = readValue(p + xyz[1].offset, xyz[1].datatype, swap);
      const double z = readValue(p + xyz[2].offset, xyz[2].datatype, swap);
      // FLOAT64 coordinates beyond float's range would become inf in the float cloud.
      if (!fitsFloat(x) || !fitsFloat(y) || !fitsFloat(z)) {
        ++out->nonfinite_points;
        continue;
      }
      out->points_S.push_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
      if (without_evidence) continue;
      err = readPointEvidence(p, fields, C, swap, options, size_t(v) * msg.width + u, &scratch,
                              &row);
      if (!err.empty()) return err;
      out->evidence.insert(out->evidence.end(), row.begin(), row.end());
    }
  }
  return out->points_S.size() > 0 ? "" : noFinitePoints(out->nonfinite_points);
}

}  // namespace evidential_octomap
