// PointCloud2 <-> core conversions, without a roscore (grid_map_ros style).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include "conversions.h"
#include "view_chunks.h"
#include "evidential_octomap/io.h"
#include "visualization.h"

using namespace evidential_octomap;
using sensor_msgs::PointField;

namespace {

// A cloud builder: fields are laid out in the order given, with optional padding per point.
struct CloudSpec {
  struct Field {
    std::string name;
    uint8_t type;
    uint32_t count;
  };
  std::vector<Field> fields;
  uint32_t padding = 0;
};

size_t sizeOf(uint8_t t) {
  return t == PointField::FLOAT64 ? 8 : (t == PointField::UINT8 || t == PointField::INT8) ? 1
         : (t == PointField::UINT16 || t == PointField::INT16)                           ? 2
                                                                                         : 4;
}

sensor_msgs::PointCloud2 makeCloud(const CloudSpec& spec, size_t n) {
  sensor_msgs::PointCloud2 msg;
  uint32_t offset = 0;
  for (const auto& f : spec.fields) {
    PointField pf;
    pf.name = f.name;
    pf.datatype = f.type;
    pf.count = f.count;
    pf.offset = offset;
    offset += sizeOf(f.type) * f.count;
    msg.fields.push_back(pf);
  }
  msg.point_step = offset + spec.padding;
  msg.width = n;
  msg.height = 1;
  msg.row_step = msg.point_step * n;
  msg.data.assign(msg.row_step, 0);
  return msg;
}

template <typename T>
void put(sensor_msgs::PointCloud2* msg, size_t point, const std::string& field, uint32_t index,
         T value) {
  for (const auto& f : msg->fields)
    if (f.name == field) {
      std::memcpy(msg->data.data() + point * msg->point_step + f.offset + index * sizeof(T), &value,
                  sizeof(T));
      return;
    }
  ADD_FAILURE() << "no field " << field;
}

constexpr int kC = 4;

// n points at (i, 2i, 3i) with `evidence` (count C): point i has evidence 5 on class i % C.
sensor_msgs::PointCloud2 evidenceCloud(size_t n, uint32_t padding = 0) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1},
                  {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1},
                  {"evidence", PointField::FLOAT32, kC}},
                 padding};
  auto msg = makeCloud(spec, n);
  for (size_t i = 0; i < n; ++i) {
    put<float>(&msg, i, "x", 0, float(i));
    put<float>(&msg, i, "y", 0, float(2 * i));
    put<float>(&msg, i, "z", 0, float(3 * i));
    put<float>(&msg, i, "evidence", i % kC, 5.f);
  }
  return msg;
}

CloudReadOptions options(EvidenceInput input = EvidenceInput::kAuto) {
  CloudReadOptions o;
  o.num_classes = kC;
  o.input = input;
  o.label_magnitude = 7.f;
  return o;
}

}  // namespace

TEST(FromPointCloud2, ReadsEvidenceFieldWithCountC) {
  SemanticCloud out;
  ASSERT_EQ(fromPointCloud2(evidenceCloud(6), options(), &out), "");
  ASSERT_EQ(out.points_S.size(), 6u);
  ASSERT_EQ(out.evidence.size(), 6u * kC);
  EXPECT_EQ(out.source, "evidence[4]");
  for (size_t i = 0; i < 6; ++i) {
    EXPECT_FLOAT_EQ(out.points_S[i].y(), 2.f * i);
    for (int c = 0; c < kC; ++c)
      EXPECT_FLOAT_EQ(out.evidence[i * kC + c], c == int(i % kC) ? 5.f : 0.f);
  }
}

TEST(FromPointCloud2, AnyPointStepAndFieldOrder) {
  // Evidence first, then z, y, x, with 13 bytes of padding per point.
  CloudSpec spec{{{"evidence", PointField::FLOAT32, kC},
                  {"z", PointField::FLOAT32, 1},
                  {"y", PointField::FLOAT32, 1},
                  {"x", PointField::FLOAT32, 1}},
                 13};
  auto msg = makeCloud(spec, 3);
  for (size_t i = 0; i < 3; ++i) {
    put<float>(&msg, i, "x", 0, 1.f + i);
    put<float>(&msg, i, "z", 0, -1.f);
    put<float>(&msg, i, "evidence", 2, 3.f);
  }
  SemanticCloud out;
  ASSERT_EQ(fromPointCloud2(msg, options(), &out), "");
  EXPECT_FLOAT_EQ(out.points_S[2].x(), 3.f);
  EXPECT_FLOAT_EQ(out.points_S[2].z(), -1.f);
  EXPECT_FLOAT_EQ(out.evidence[2 * kC + 2], 3.f);
}

TEST(FromPointCloud2, ReadsPerClassEvidenceFields) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1}, {"z", PointField::FLOAT32, 1}}};
  for (int c = kC - 1; c >= 0; --c)  // reversed order: found by name, not position
    spec.fields.push_back({"evidence_" + std::to_string(c), PointField::FLOAT32, 1});
  auto msg = makeCloud(spec, 2);
  put<float>(&msg, 1, "evidence_3", 0, 9.f);
  SemanticCloud out;
  ASSERT_EQ(fromPointCloud2(msg, options(EvidenceInput::kEvidence), &out), "");
  EXPECT_FLOAT_EQ(out.evidence[1 * kC + 3], 9.f);
  EXPECT_FLOAT_EQ(out.evidence[1 * kC + 0], 0.f);
}

TEST(FromPointCloud2, Float64EvidenceBeyondFloatRangeIsRejectedWithThePoint) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}}};
  for (int c = 0; c < kC; ++c)
    spec.fields.push_back({"evidence_" + std::to_string(c), PointField::FLOAT64, 1});
  auto msg = makeCloud(spec, 2);
  put<double>(&msg, 1, "evidence_2", 0, 1e300);
  SemanticCloud out;
  const std::string err = fromPointCloud2(msg, options(EvidenceInput::kEvidence), &out);
  EXPECT_NE(err.find("point 1: evidence of class 2"), std::string::npos) << err;
  EXPECT_NE(err.find("within float range"), std::string::npos) << err;
}

TEST(FromPointCloud2, AlphaBecomesAlphaMinusOne) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"alpha", PointField::FLOAT32, kC}}};
  auto msg = makeCloud(spec, 1);
  for (int c = 0; c < kC; ++c) put<float>(&msg, 0, "alpha", c, 1.f + c);
  SemanticCloud out;
  ASSERT_EQ(fromPointCloud2(msg, options(), &out), "");
  EXPECT_EQ(out.source, "alpha[4]");
  for (int c = 0; c < kC; ++c) EXPECT_FLOAT_EQ(out.evidence[c], float(c));
}

TEST(FromPointCloud2, AlphaBelowOneIsRejected) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"alpha", PointField::FLOAT32, kC}}};
  auto msg = makeCloud(spec, 1);  // alpha = 0 everywhere
  SemanticCloud out;
  const std::string err = fromPointCloud2(msg, options(), &out);
  EXPECT_NE(err.find("alpha must be finite and >= 1"), std::string::npos) << err;
}

TEST(FromPointCloud2, LogitsBecomeEvidenceByTheChosenTransform) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"logits", PointField::FLOAT32, kC}}};
  auto msg = makeCloud(spec, 1);
  const float z[kC] = {1.f, 3.f, 0.f, -2.f};
  for (int c = 0; c < kC; ++c) put<float>(&msg, 0, "logits", c, z[c]);
  SemanticCloud out;
  CloudReadOptions o = options();
  o.logit_transform = LogitTransform::kExp;
  ASSERT_EQ(fromPointCloud2(msg, o, &out), "");
  EXPECT_EQ(out.source, "logits[4] (exp)");
  for (int c = 0; c < kC; ++c) EXPECT_NEAR(out.evidence[c], std::exp(z[c]), 1e-4);
  // softmax (the default): confidence-scaled evidence of p = softmax(z), computed by hand.
  o.logit_transform = LogitTransform::kSoftmax;
  o.probability_magnitude = 10.f;
  ASSERT_EQ(fromPointCloud2(msg, o, &out), "");
  double sum = 0;
  for (float v : z) sum += std::exp(v);
  const double confidence = (kC * std::exp(3.0) / sum - 1.0) / (kC - 1);
  for (int c = 0; c < kC; ++c)
    EXPECT_NEAR(out.evidence[c], 10.0 * std::exp(z[c]) / sum * confidence, 1e-5);
}

TEST(FromPointCloud2, ProbabilitiesBecomeConfidenceScaledEvidence) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"probabilities", PointField::FLOAT32, kC}}};
  auto msg = makeCloud(spec, 2);
  const float p[kC] = {0.1f, 0.7f, 0.1f, 0.1f};
  for (int c = 0; c < kC; ++c) put<float>(&msg, 0, "probabilities", c, p[c]);
  put<float>(&msg, 1, "probabilities", 0, -0.5f);  // invalid
  SemanticCloud out;
  const std::string err = fromPointCloud2(msg, options(), &out);
  EXPECT_NE(err.find("point 1: probability of class 0"), std::string::npos) << err;
  put<float>(&msg, 1, "probabilities", 0, 1.f);
  ASSERT_EQ(fromPointCloud2(msg, options(), &out), "");
  EXPECT_EQ(out.source, "probabilities[4]");
  const double confidence = (kC * 0.7 - 1.0) / (kC - 1);  // 0.6
  for (int c = 0; c < kC; ++c) EXPECT_NEAR(out.evidence[c], 20.0 * p[c] * confidence, 1e-5);
  for (int c = 0; c < kC; ++c) EXPECT_NEAR(out.evidence[kC + c], c == 0 ? 20.f : 0.f, 1e-5);
}

TEST(FromPointCloud2, LabelOfAnyIntegerTypeIsOneHot) {
  for (uint8_t type : {PointField::UINT8, PointField::UINT16, PointField::INT32, PointField::UINT32,
                       PointField::FLOAT32}) {
    CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                    {"z", PointField::FLOAT32, 1}, {"label", type, 1}}};
    auto msg = makeCloud(spec, 1);
    switch (type) {
      case PointField::UINT8: put<uint8_t>(&msg, 0, "label", 0, 2); break;
      case PointField::UINT16: put<uint16_t>(&msg, 0, "label", 0, 2); break;
      case PointField::INT32: put<int32_t>(&msg, 0, "label", 0, 2); break;
      case PointField::UINT32: put<uint32_t>(&msg, 0, "label", 0, 2); break;
      default: put<float>(&msg, 0, "label", 0, 2.f); break;
    }
    SemanticCloud out;
    ASSERT_EQ(fromPointCloud2(msg, options(), &out), "") << int(type);
    EXPECT_EQ(out.source, "label");
    for (int c = 0; c < kC; ++c) EXPECT_FLOAT_EQ(out.evidence[c], c == 2 ? 7.f : 0.f) << int(type);
  }
}

TEST(FromPointCloud2, RawLabelsGoThroughTheLearningMap) {
  ClassTable table;
  table.names = {"a", "b", "c", "d"};
  table.learning_map = {{40, 3}, {10, 1}};
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"label", PointField::UINT32, 1}}};
  auto msg = makeCloud(spec, 2);
  put<uint32_t>(&msg, 0, "label", 0, 40);
  put<uint32_t>(&msg, 1, "label", 0, 99);
  auto o = options(EvidenceInput::kLabel);
  o.raw_label_table = &table;
  SemanticCloud out;
  const std::string err = fromPointCloud2(msg, o, &out);
  EXPECT_NE(err.find("point 1"), std::string::npos) << err;  // 99 is not in the map
  put<uint32_t>(&msg, 1, "label", 0, 10);
  ASSERT_EQ(fromPointCloud2(msg, o, &out), "");
  EXPECT_FLOAT_EQ(out.evidence[0 * kC + 3], 7.f);
  EXPECT_FLOAT_EQ(out.evidence[1 * kC + 1], 7.f);
}

TEST(FromPointCloud2, LabelOutOfRangeIsRejected) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"label", PointField::INT32, 1}}};
  auto msg = makeCloud(spec, 2);
  put<int32_t>(&msg, 1, "label", 0, kC);
  SemanticCloud out;
  EXPECT_NE(fromPointCloud2(msg, options(), &out).find("outside [0, 4)"), std::string::npos);
  put<int32_t>(&msg, 1, "label", 0, -1);
  EXPECT_NE(fromPointCloud2(msg, options(), &out).find("not a non-negative integer"),
            std::string::npos);
}

// Issue 16 item 5: labels of 2^31 and more were cast to int (undefined) and mapped as
// occupancy-only points without a word; label 20 (>= C) was refused. All are refused now.
TEST(FromPointCloud2, HugeLabelsAreRefusedLikeLabelsBeyondC) {
  SemanticCloud out;
  {
    CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                    {"z", PointField::FLOAT32, 1}, {"label", PointField::UINT32, 1}}};
    auto msg = makeCloud(spec, 3);
    for (uint32_t label : {4294967295u, 2147483648u, 2147483647u}) {
      put<uint32_t>(&msg, 2, "label", 0, label);
      const std::string err = fromPointCloud2(msg, options(), &out);
      EXPECT_NE(err.find("point 2: label " + std::to_string(label) + " is outside [0, 4)"),
                std::string::npos)
          << label << ": " << err;
    }
  }
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"label", PointField::FLOAT64, 1}}};
  auto msg = makeCloud(spec, 3);
  for (double label : {1e300, 4294967296.0, 2147483648.0}) {
    put<double>(&msg, 1, "label", 0, label);
    const std::string err = fromPointCloud2(msg, options(), &out);
    EXPECT_NE(err.find("is outside [0, 4)"), std::string::npos) << label << ": " << err;
  }
}

TEST(FromPointCloud2, MissingFieldIsNamed) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"intensity", PointField::FLOAT32, 1}}};
  auto msg = makeCloud(spec, 2);
  SemanticCloud out;
  const std::string err = fromPointCloud2(msg, options(), &out);
  EXPECT_NE(err.find("no semantic field"), std::string::npos) << err;
  EXPECT_NE(err.find("intensity"), std::string::npos) << err;  // lists what is there
  const std::string err_ev = fromPointCloud2(msg, options(EvidenceInput::kEvidence), &out);
  EXPECT_NE(err_ev.find("missing field 'evidence'"), std::string::npos) << err_ev;

  CloudSpec no_z{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"evidence", PointField::FLOAT32, kC}}};
  EXPECT_NE(fromPointCloud2(makeCloud(no_z, 1), options(), &out).find("missing field 'z'"),
            std::string::npos);
}

TEST(FromPointCloud2, WrongEvidenceCountIsRejected) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"evidence", PointField::FLOAT32, kC + 1}}};
  SemanticCloud out;
  const std::string err = fromPointCloud2(makeCloud(spec, 1), options(), &out);
  EXPECT_NE(err.find("count 5, expected C = 4"), std::string::npos) << err;
}

TEST(FromPointCloud2, MissingOrExtraPerClassFieldIsRejected) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"evidence_0", PointField::FLOAT32, 1},
                  {"evidence_1", PointField::FLOAT32, 1}}};
  SemanticCloud out;
  std::string err = fromPointCloud2(makeCloud(spec, 1), options(), &out);
  EXPECT_NE(err.find("'evidence_2' is missing"), std::string::npos) << err;
  for (int c = 2; c <= kC; ++c)
    spec.fields.push_back({"evidence_" + std::to_string(c), PointField::FLOAT32, 1});
  err = fromPointCloud2(makeCloud(spec, 1), options(), &out);
  EXPECT_NE(err.find("more than C = 4"), std::string::npos) << err;
}

TEST(FromPointCloud2, NonFloatEvidenceIsRejected) {
  CloudSpec spec{{{"x", PointField::FLOAT32, 1}, {"y", PointField::FLOAT32, 1},
                  {"z", PointField::FLOAT32, 1}, {"evidence", PointField::UINT8, kC}}};
  SemanticCloud out;
  const std::string err = fromPointCloud2(makeCloud(spec, 1), options(), &out);
  EXPECT_NE(err.find("must be float32"), std::string::npos) << err;
}

TEST(FromPointCloud2, NanInfAndNegativeEvidenceAreRejectedWithThePoint) {
  const float bad[3] = {std::numeric_limits<float>::quiet_NaN(),
                        std::numeric_limits<float>::infinity(), -0.5f};
  for (float value : bad) {
    auto msg = evidenceCloud(5);
    put<float>(&msg, 3, "evidence", 1, value);
    SemanticCloud out;
    const std::string err = fromPointCloud2(msg, options(), &out);
    EXPECT_NE(err.find("point 3: evidence of class 1"), std::string::npos) << err;
    EXPECT_NE(err.find("finite and >= 0"), std::string::npos) << err;
  }
}

TEST(FromPointCloud2, TruncatedDataIsRejected) {
  auto msg = evidenceCloud(5);
  msg.data.resize(msg.data.size() - 1);
  SemanticCloud out;
  const std::string err = fromPointCloud2(msg, options(), &out);
  EXPECT_NE(err.find("truncated data"), std::string::npos) << err;
}

TEST(FromPointCloud2, FieldBeyondPointStepIsRejected) {
  auto msg = evidenceCloud(2);
  msg.point_step = 20;  // evidence (offset 12, 16 bytes) no longer fits
  msg.row_step = 40;
  SemanticCloud out;
  const std::string err = fromPointCloud2(msg, options(), &out);
  EXPECT_NE(err.find("does not fit point_step"), std::string::npos) << err;
}

TEST(FromPointCloud2, ZeroPointsIsRejected) {
  SemanticCloud out;
  EXPECT_EQ(fromPointCloud2(evidenceCloud(0), options(), &out), "cloud has zero points");
}

TEST(FromPointCloud2, NonFinitePointsAreDroppedAndCounted) {
  auto msg = evidenceCloud(4, 8);
  put<float>(&msg, 1, "x", 0, std::numeric_limits<float>::quiet_NaN());
  SemanticCloud out;
  ASSERT_EQ(fromPointCloud2(msg, options(), &out), "");
  EXPECT_EQ(out.points_S.size(), 3u);
  EXPECT_EQ(out.nonfinite_points, 1u);
  EXPECT_FLOAT_EQ(out.points_S[1].x(), 2.f);               // point 2 moved up
  EXPECT_FLOAT_EQ(out.evidence[1 * kC + 2], 5.f);          // with its own evidence
}

// Found by fuzz_pointcloud2: a FLOAT64 coordinate of 1e300 is finite as a double but not as
// the float the cloud stores; the point came back as inf.
TEST(FromPointCloud2, Float64CoordinatesBeyondFloatRangeAreDroppedAndCounted) {
  CloudSpec spec{{{"x", PointField::FLOAT64, 1},
                  {"y", PointField::FLOAT64, 1},
                  {"z", PointField::FLOAT64, 1},
                  {"evidence", PointField::FLOAT32, kC}}};
  auto msg = makeCloud(spec, 3);
  put<double>(&msg, 0, "x", 0, 1e300);
  put<double>(&msg, 1, "z", 0, -4e38);
  put<double>(&msg, 2, "y", 0, 3e38);  // still a float (FLT_MAX = 3.4e38)
  SemanticCloud out;
  ASSERT_EQ(fromPointCloud2(msg, options(), &out), "");
  ASSERT_EQ(out.points_S.size(), 1u);
  EXPECT_EQ(out.nonfinite_points, 2u);
  EXPECT_FLOAT_EQ(out.points_S[0].y(), 3e38f);
}

TEST(FromPointCloud2, OrganisedCloudWithRowPadding) {
  auto flat = evidenceCloud(6);
  sensor_msgs::PointCloud2 msg = flat;
  msg.width = 3;
  msg.height = 2;
  msg.row_step = 3 * msg.point_step + 10;
  msg.data.assign(msg.row_step * 2, 0);
  for (int r = 0; r < 2; ++r)
    std::memcpy(msg.data.data() + r * msg.row_step, flat.data.data() + r * 3 * flat.point_step,
                3 * flat.point_step);
  SemanticCloud out;
  ASSERT_EQ(fromPointCloud2(msg, options(), &out), "");
  ASSERT_EQ(out.points_S.size(), 6u);
  EXPECT_FLOAT_EQ(out.points_S[4].x(), 4.f);
  EXPECT_FLOAT_EQ(out.evidence[5 * kC + 1], 5.f);
}

TEST(FromPointCloud2, BigEndianCloudsAreSwapped) {
  auto msg = evidenceCloud(2);
  for (size_t i = 0; i + 4 <= msg.data.size(); i += 4) std::swap(msg.data[i], msg.data[i + 3]),
                                                       std::swap(msg.data[i + 1], msg.data[i + 2]);
  msg.is_bigendian = true;
  SemanticCloud out;
  ASSERT_EQ(fromPointCloud2(msg, options(), &out), "");
  EXPECT_FLOAT_EQ(out.points_S[1].z(), 3.f);
  EXPECT_FLOAT_EQ(out.evidence[1 * kC + 1], 5.f);
}

// The common layout (float32 x, y, z and evidence, host order) has a reader of its own; the
// same points big-endian go through the general one. Both must give the same cloud.
TEST(FromPointCloud2, PackedAndGeneralReadersGiveTheSameCloud) {
  const size_t n = 300;
  auto packed = evidenceCloud(n, 4);
  uint32_t state = 12345;
  auto next = [&] { return (state = state * 1664525u + 1013904223u) >> 8; };
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < kC; ++c) put<float>(&packed, i, "evidence", c, float(next() % 1000) / 7.f);
    if (next() % 10 == 0)
      put<float>(&packed, i, "z", 0, std::numeric_limits<float>::infinity());
  }
  sensor_msgs::PointCloud2 swapped = packed;
  for (size_t i = 0; i + 4 <= swapped.data.size(); i += 4)
    std::swap(swapped.data[i], swapped.data[i + 3]), std::swap(swapped.data[i + 1], swapped.data[i + 2]);
  swapped.is_bigendian = true;
  SemanticCloud a, b;
  ASSERT_EQ(fromPointCloud2(packed, options(), &a), "");
  ASSERT_EQ(fromPointCloud2(swapped, options(), &b), "");
  ASSERT_GT(a.nonfinite_points, 0u);
  EXPECT_EQ(a.nonfinite_points, b.nonfinite_points);
  ASSERT_EQ(a.points_S.size(), b.points_S.size());
  for (size_t i = 0; i < a.points_S.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.points_S[i](k), b.points_S[i](k));
  EXPECT_EQ(a.evidence, b.evidence);
}

TEST(EvidenceInputName, UnknownNameThrows) {
  EXPECT_EQ(evidenceInputFromName("alpha"), EvidenceInput::kAlpha);
  EXPECT_EQ(evidenceInputFromName("logits"), EvidenceInput::kLogits);
  EXPECT_EQ(evidenceInputFromName("probabilities"), EvidenceInput::kProbabilities);
  EXPECT_THROW(evidenceInputFromName("softmax"), std::invalid_argument);
}

// --- tree -> views ------------------------------------------------------------------------

namespace {

ClassTable fourClasses() {
  ClassTable t;
  t.names = {"a", "b", "c", "d"};
  t.colors = {{{10, 0, 0}}, {{0, 20, 0}}, {{0, 0, 30}}, {{40, 40, 40}}};
  return t;
}

// A small map: a wall of class 2 seen from the origin.
std::unique_ptr<EvidentialOcTree> wallMap() {
  auto tree = std::make_unique<EvidentialOcTree>(0.2, kC);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (float y = -1.f; y <= 1.f; y += 0.1f)
    for (float z = -0.5f; z <= 0.5f; z += 0.1f) {
      points.push_back(3.05f, y, z);
      for (int c = 0; c < kC; ++c) evidence.push_back(c == 2 ? 30.f : 0.f);
    }
  tree->insertSemanticScan(points, evidence, octomap::point3d(0, 0, 0));
  return tree;
}

}  // namespace

TEST(OccupiedVoxels, WallVoxelsCarryTheWallClass) {
  auto tree = wallMap();
  const auto voxels = occupiedVoxels(*tree);
  ASSERT_FALSE(voxels.empty());
  size_t labelled = 0, confident = 0;
  for (const auto& v : voxels) {
    EXPECT_TRUE(tree->isNodeOccupied(tree->search(v.center)));
    if (v.label >= 0) {
      ++labelled;
      EXPECT_EQ(v.label, 2);
      EXPECT_GT(v.uncertainty, 0.f);
      EXPECT_LE(v.uncertainty, 1.f);  // voxels at the kernel's edge may round to 1
      if (v.uncertainty < 0.5f) ++confident;
    }
  }
  EXPECT_GT(labelled, 0u);
  EXPECT_GT(confident, 0u);
}

TEST(OccupiedVoxels, BoxLimitsTheVoxels) {
  auto tree = wallMap();
  Box box;
  box.min = octomap::point3d(2.5f, 0.f, -1.f);
  box.max = octomap::point3d(3.5f, 1.5f, 1.f);
  const auto all = occupiedVoxels(*tree);
  const auto some = occupiedVoxels(*tree, box);
  ASSERT_FALSE(some.empty());
  EXPECT_LT(some.size(), all.size());
  for (const auto& v : some) EXPECT_GE(v.center.y(), 0.f - 0.2f);
}

TEST(MapMessages, EvidentialMapReadsBackAsTheSameTree) {
  auto tree = wallMap();
  const EvidentialMap msg = toEvidentialMap(*tree, "map");
  EXPECT_EQ(msg.header.frame_id, "map");
  EXPECT_EQ(msg.num_classes, kC);
  EXPECT_EQ(msg.fusion_rule, "dempster");
  EXPECT_DOUBLE_EQ(msg.resolution, 0.2);
  std::stringstream s(std::string(msg.data.begin(), msg.data.end()));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(s));
  auto* back = dynamic_cast<EvidentialOcTree*>(read.get());
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->getNumLeafNodes(), tree->getNumLeafNodes());
  EXPECT_EQ(back->query(octomap::point3d(3.05f, 0.f, 0.f)).label, 2);
}

TEST(MapMessages, OccupancyMapIsAPlainOcTreeBinary) {
  auto tree = wallMap();
  const OccupancyMap msg = toOccupancyMap(*tree, "map");
  std::stringstream s(std::string(msg.data.begin(), msg.data.end()));
  octomap::OcTree plain(0.1);
  ASSERT_TRUE(plain.readBinary(s));
  EXPECT_DOUBLE_EQ(plain.getResolution(), 0.2);
  const auto* node = plain.search(3.05, 0.0, 0.0);
  ASSERT_NE(node, nullptr);
  EXPECT_TRUE(plain.isNodeOccupied(node));
}

TEST(ToPointCloud2, FieldsHoldLabelUncertaintyAndClassColour) {
  std::vector<VoxelView> voxels(2);
  voxels[0].center = octomap::point3d(1, 2, 3);
  voxels[0].label = 1;
  voxels[0].uncertainty = 0.25f;
  voxels[0].conflict = 0.125f;
  voxels[0].error_probability = 0.375f;
  voxels[1].label = -1;
  const auto msg = toPointCloud2(voxels, fourClasses(), "map");
  ASSERT_EQ(msg.width, 2u);
  ASSERT_EQ(msg.fields.size(), 8u);
  EXPECT_EQ(msg.fields[6].name, "conflict");
  EXPECT_EQ(msg.fields[7].name, "error_probability");
  float conflict, error_probability;
  std::memcpy(&conflict, msg.data.data() + msg.fields[6].offset, 4);
  std::memcpy(&error_probability, msg.data.data() + msg.fields[7].offset, 4);
  EXPECT_FLOAT_EQ(conflict, 0.125f);
  EXPECT_FLOAT_EQ(error_probability, 0.375f);
  EXPECT_EQ(msg.point_step, 32u);
  EXPECT_EQ(msg.header.frame_id, "map");
  // Read it back through the same reader's layout rules.
  int32_t label;
  float u, rgb, y;
  std::memcpy(&y, msg.data.data() + msg.fields[1].offset, 4);
  std::memcpy(&label, msg.data.data() + msg.fields[3].offset, 4);
  std::memcpy(&u, msg.data.data() + msg.fields[4].offset, 4);
  std::memcpy(&rgb, msg.data.data() + msg.fields[5].offset, 4);
  EXPECT_EQ(msg.fields[3].name, "label");
  EXPECT_EQ(msg.fields[3].datatype, PointField::INT32);
  EXPECT_EQ(msg.fields[4].name, "uncertainty");
  EXPECT_EQ(msg.fields[5].name, "rgb");
  EXPECT_FLOAT_EQ(y, 2.f);
  EXPECT_EQ(label, 1);
  EXPECT_FLOAT_EQ(u, 0.25f);
  uint32_t packed;
  std::memcpy(&packed, &rgb, 4);
  EXPECT_EQ(packed, (0u << 16) | (20u << 8) | 0u);
  std::memcpy(&label, msg.data.data() + msg.point_step + msg.fields[3].offset, 4);
  EXPECT_EQ(label, -1);
}

TEST(SemanticMarkers, OneCubeListPerDepthColouredByClass) {
  std::vector<VoxelView> voxels(3);
  for (int i = 0; i < 3; ++i) {
    voxels[i].depth = 16;
    voxels[i].size = 0.2;
    voxels[i].label = i == 2 ? -1 : 2;
  }
  const auto array = semanticMarkers(voxels, fourClasses(), "map", 16);
  ASSERT_EQ(array.markers.size(), 17u);
  const auto& m = array.markers[16];
  EXPECT_EQ(m.type, visualization_msgs::Marker::CUBE_LIST);
  EXPECT_EQ(m.action, visualization_msgs::Marker::ADD);
  ASSERT_EQ(m.points.size(), 3u);
  EXPECT_FLOAT_EQ(m.colors[0].b, 30.f / 255.f);
  EXPECT_FLOAT_EQ(m.colors[2].r, 128.f / 255.f);  // unlabelled: grey
  EXPECT_DOUBLE_EQ(m.scale.x, 0.2);
  EXPECT_EQ(array.markers[3].action, visualization_msgs::Marker::DELETE);
}

TEST(UncertaintyMarkers, ColoursFollowTheUncertaintyColourMap) {
  std::vector<VoxelView> voxels(2);
  voxels[0].depth = voxels[1].depth = 16;
  voxels[0].uncertainty = 0.f;
  voxels[1].uncertainty = 1.f;
  UncertaintyRange fixed;
  const auto array = uncertaintyMarkers(voxels, fixed, UncertaintyView::kVacuity, "map", 16);
  const auto lo = uncertaintyColor(0.0), hi = uncertaintyColor(1.0);
  EXPECT_FLOAT_EQ(array.markers[16].colors[0].r, lo[0] / 255.f);
  EXPECT_FLOAT_EQ(array.markers[16].colors[1].r, hi[0] / 255.f);
  EXPECT_FLOAT_EQ(array.markers[16].colors[1].b, hi[2] / 255.f);
  // Automatic range: 0.2 .. 0.4 spans the whole colour map.
  voxels[0].uncertainty = 0.2f;
  voxels[1].uncertainty = 0.4f;
  UncertaintyRange automatic;
  automatic.automatic = true;
  const auto scaled = uncertaintyMarkers(voxels, automatic, UncertaintyView::kVacuity, "map", 16);
  EXPECT_FLOAT_EQ(scaled.markers[16].colors[1].r, hi[0] / 255.f);
  EXPECT_FLOAT_EQ(scaled.markers[16].colors[0].g, lo[1] / 255.f);
}

TEST(UncertaintyMarkers, TheViewChoosesErrorProbabilityOrVacuity) {
  std::vector<VoxelView> voxels(2);
  voxels[0].depth = voxels[1].depth = 16;
  voxels[0].uncertainty = voxels[1].uncertainty = 0.5f;  // the same vacuity
  voxels[0].error_probability = 0.f;
  voxels[1].error_probability = 1.f;
  const auto lo = uncertaintyColor(0.0), hi = uncertaintyColor(1.0), mid = uncertaintyColor(0.5);
  const auto errors = uncertaintyMarkers(voxels, UncertaintyRange(),
                                         uncertaintyViewFromName("error_probability"), "map", 16);
  EXPECT_FLOAT_EQ(errors.markers[16].colors[0].g, lo[1] / 255.f);
  EXPECT_FLOAT_EQ(errors.markers[16].colors[1].r, hi[0] / 255.f);
  const auto vacuity = uncertaintyMarkers(voxels, UncertaintyRange(),
                                          uncertaintyViewFromName("vacuity"), "map", 16);
  EXPECT_FLOAT_EQ(vacuity.markers[16].colors[0].r, mid[0] / 255.f);
  EXPECT_FLOAT_EQ(vacuity.markers[16].colors[1].r, mid[0] / 255.f);
  EXPECT_THROW(uncertaintyViewFromName("u"), std::invalid_argument);
}

// Each occupied voxel's error probability is 1 - max_c (b^c + u / C) of its own opinion.
TEST(LeafViews, ErrorProbabilityIsOneMinusTheLargestProjectedProbability) {
  auto tree = wallMap();
  size_t labelled = 0;
  for (const auto& v : occupiedVoxels(*tree)) {
    if (v.label < 0) continue;
    ++labelled;
    const VoxelOpinion o = tree->opinion(tree->search(v.center, v.depth));
    double best = 0.0;
    for (float b : o.belief) best = std::max(best, double(b) + double(o.uncertainty) / kC);
    EXPECT_NEAR(v.error_probability, 1.0 - best, 1e-6);
    EXPECT_LT(v.error_probability, 1.0 - 1.0 / kC + 1e-6);
  }
  EXPECT_GT(labelled, 10u);
}

TEST(ConflictMarkers, ColoursFollowTheColourMapOverZeroToOne) {
  std::vector<VoxelView> voxels(2);
  voxels[0].depth = voxels[1].depth = 16;
  voxels[0].conflict = 0.f;
  voxels[1].conflict = 0.5f;
  const auto array = conflictMarkers(voxels, "map", 16);
  const auto lo = uncertaintyColor(0.0), mid = uncertaintyColor(0.5);
  EXPECT_EQ(array.markers[16].ns, "conflict");
  EXPECT_FLOAT_EQ(array.markers[16].colors[0].g, lo[1] / 255.f);
  EXPECT_FLOAT_EQ(array.markers[16].colors[1].r, mid[0] / 255.f);
}

TEST(LeafViews, OccupiedAndFreeLeavesPartitionTheKnownLeaves) {
  auto tree = wallMap();
  const auto occupied = occupiedVoxels(*tree), free = freeVoxels(*tree);
  EXPECT_GT(occupied.size(), 50u);
  EXPECT_GT(free.size(), 50u);
  EXPECT_EQ(occupied.size() + free.size(), tree->getNumLeafNodes());
  for (const auto& v : free) {
    EXPECT_FALSE(tree->isNodeOccupied(tree->search(v.center, v.depth)));
    EXPECT_EQ(v.label, -1);
  }
  const auto free_markers = freeMarkers(free, "map", 16);
  size_t cubes = 0;
  for (const auto& m : free_markers.markers) cubes += m.points.size();
  EXPECT_EQ(cubes, free.size());
}

TEST(LeafViews, HeightBandKeepsLeavesWhoseCentreIsInside) {
  auto tree = wallMap();  // wall voxels from z = -0.5 to 0.5
  HeightBand band;
  band.min_z = 0.0;
  const auto above = occupiedVoxels(*tree, Box(), band);
  ASSERT_GT(above.size(), 10u);
  for (const auto& v : above) EXPECT_GE(v.center.z(), 0.0);
  EXPECT_LT(above.size(), occupiedVoxels(*tree).size());
}

// A map wider than many view chunks (12.8 m at 0.2 m): walls 30 m either side of the sensor,
// so the free space between them is pruned into leaves larger than a chunk.
std::unique_ptr<EvidentialOcTree> wideMap() {
  auto tree = std::make_unique<EvidentialOcTree>(0.2, kC);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (float x : {-30.05f, 30.05f})
    for (float y = -20.f; y <= 20.f; y += 0.15f)
      for (float z = -1.f; z <= 1.f; z += 0.15f) {
        points.push_back(x, y, z);
        for (int c = 0; c < kC; ++c) evidence.push_back(c == (x > 0 ? 1 : 2) ? 30.f : 0.f);
      }
  tree->insertSemanticScan(points, evidence, octomap::point3d(0, 0, 0));
  return tree;
}

// Sets every voxel of the 25.6 m cube at the key origin free, so it is pruned into one leaf of
// depth kChunkDepth - 1: larger than a chunk. `by_chunk`: its eight chunks alternate between two
// free values, so each is one leaf of depth kChunkDepth and the cube is not pruned further.
void fillFreeCube(EvidentialOcTree* tree, bool by_chunk = false) {
  const octomap::OcTreeKey origin = tree->coordToKey(octomap::point3d(0.1f, 0.1f, 0.1f));
  const unsigned chunk = 1u << (tree->getTreeDepth() - kChunkDepth), edge = 2 * chunk;
  const float free_value = tree->getClampingThresMinLog();
  octomap::OcTreeKey k;
  for (unsigned x = 0; x < edge; ++x)
    for (unsigned y = 0; y < edge; ++y)
      for (unsigned z = 0; z < edge; ++z) {
        k[0] = uint16_t(origin[0] + x), k[1] = uint16_t(origin[1] + y);
        k[2] = uint16_t(origin[2] + z);
        const bool odd = by_chunk && ((x / chunk + y / chunk + z / chunk) & 1);
        tree->setNodeValue(k, odd ? free_value / 2 : free_value, true);
      }
  tree->prune();
}

using LeafId = std::tuple<uint16_t, uint16_t, uint16_t, unsigned>;

std::multiset<LeafId> leafIds(const EvidentialOcTree& tree, const std::vector<VoxelView>& views) {
  std::multiset<LeafId> ids;
  for (const auto& v : views) {
    const octomap::OcTreeKey k = tree.coordToKey(v.center, v.depth);
    ids.emplace(k[0], k[1], k[2], v.depth);
  }
  return ids;
}

TEST(ViewChunks, ChunksReadEveryLeafOnceAsOneWalkOverTheTree) {
  auto tree = wideMap();
  fillFreeCube(tree.get());
  std::vector<VoxelView> walked_occupied, walked_free;  // the reference: one walk, no chunks
  size_t pruned_larger_than_a_chunk = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    VoxelView v;
    v.center = it.getCoordinate();
    v.depth = it.getDepth();
    (tree->isNodeOccupied(*it) ? walked_occupied : walked_free).push_back(v);
    if (it.getDepth() < kChunkDepth) ++pruned_larger_than_a_chunk;
  }
  ASSERT_GT(pruned_larger_than_a_chunk, 0u);
  const auto chunks = viewChunks(*tree, Box());
  ASSERT_GT(chunks.size(), 8u);
  std::vector<VoxelView> occupied, free;
  for (const auto& chunk : chunks) readChunk(*tree, chunk, HeightBand(), &occupied, &free);
  EXPECT_EQ(leafIds(*tree, occupied), leafIds(*tree, walked_occupied));
  EXPECT_EQ(leafIds(*tree, free), leafIds(*tree, walked_free));
  size_t labelled = 0;
  for (const auto& v : occupied) labelled += v.label >= 0;
  EXPECT_GT(labelled, occupied.size() / 2);
}

TEST(ViewChunks, ALeafPrunedAcrossChunksAfterTheyWereListedIsReadOnce) {
  auto tree = wideMap();
  fillFreeCube(tree.get(), true);
  const auto chunks = viewChunks(*tree, Box());
  // Between the listing and the reads the map changes: the cube's eight listed chunks become
  // one pruned leaf that each of them overlaps.
  fillFreeCube(tree.get());
  std::vector<VoxelView> occupied, free;
  for (const auto& chunk : chunks) readChunk(*tree, chunk, HeightBand(), &occupied, &free);
  size_t big = 0;
  for (const auto& v : free) big += v.depth == kChunkDepth - 1;
  EXPECT_EQ(big, 1u);
  const auto ids = leafIds(*tree, free);
  for (const auto& id : ids) EXPECT_EQ(ids.count(id), 1u);
}

TEST(ViewChunks, ABoxReadsTheLeavesWhoseKeysLieInIt) {
  auto tree = wideMap();
  Box box;
  box.min = octomap::point3d(25.f, -5.f, -2.f);
  box.max = octomap::point3d(35.f, 5.f, 2.f);
  const auto some = occupiedVoxels(*tree, box);
  ASSERT_FALSE(some.empty());
  const octomap::OcTreeKey lo = tree->coordToKey(box.min), hi = tree->coordToKey(box.max);
  size_t expected = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey k = it.getKey();
    bool inside = tree->isNodeOccupied(*it);
    for (int i = 0; i < 3; ++i) inside = inside && k[i] >= lo[i] && k[i] <= hi[i];
    expected += inside;
  }
  EXPECT_EQ(some.size(), expected);
  for (const auto& v : some) EXPECT_GT(v.center.x(), 24.f);
}

TEST(KeepHeightBand, KeepsPointsInsideTheBandInTheGivenFrameWithTheirEvidence) {
  SemanticCloud scan;
  const int C = 2;
  for (int i = 0; i < 5; ++i) {
    scan.points_S.push_back(0.f, 0.f, float(i));  // z_S = 0 .. 4
    scan.evidence.insert(scan.evidence.end(), {float(i), 10.f * i});
  }
  HeightBand band;
  band.min_z = 1.5;
  band.max_z = 3.5;
  // Frame F sits 1 m below the sensor: z_F = z_S + 1, so z_S 1 and 2 are inside.
  const octomap::pose6d T_F_S(0, 0, 1, 0, 0, 0);
  EXPECT_EQ(keepHeightBand(T_F_S, band, C, &scan), 3u);
  ASSERT_EQ(scan.points_S.size(), 2u);
  EXPECT_FLOAT_EQ(scan.points_S[0].z(), 1.f);
  EXPECT_FLOAT_EQ(scan.points_S[1].z(), 2.f);
  EXPECT_EQ(scan.evidence, (std::vector<float>{1.f, 10.f, 2.f, 20.f}));
  // Unbounded: nothing removed.
  EXPECT_EQ(keepHeightBand(T_F_S, HeightBand(), C, &scan), 0u);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
