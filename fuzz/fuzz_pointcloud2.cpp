// libFuzzer target: the node's PointCloud2 evidence parser, fromPointCloud2 (src/ros/
// conversions.cpp). It takes a sensor_msgs::PointCloud2, a header-only message type, so it
// builds without catkin wherever the sensor_msgs headers are installed (Debian:
// ros-sensor-msgs-dev); fuzz/CMakeLists.txt skips it otherwise.
//
// The input bytes encode a message (see decode()): options, up to 8 fields (name from a list,
// offset, datatype, count), layout, endianness, then the point data. Invariants: the parser
// returns "" or an error text; on "" every point is finite, evidence is points x C, finite and
// >= 0, and a tree accepts the cloud without std::invalid_argument.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "conversions.h"
#include "fuzz_targets.h"

namespace {

const char* const kNames[] = {"x",         "y",        "z",       "evidence", "evidence_0",
                              "evidence_1", "evidence_2", "alpha",  "alpha_0",  "alpha_1",
                              "label",     "rgb",      "intensity", "",       "evidence_3"};

struct Reader {
  const uint8_t* data;
  size_t size, at = 0;
  uint8_t u8() { return at < size ? data[at++] : 0; }
  uint16_t u16() { return uint16_t(u8() | (u8() << 8)); }
};

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  evidential_octomap::fuzz::silenceDiagnostics();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace evidential_octomap;
  Reader r{data, size};
  CloudReadOptions options;
  options.num_classes = 1 + r.u8() % 24;
  options.input = static_cast<EvidenceInput>(r.u8() % 5);
  const uint8_t flags = r.u8();
  options.label_magnitude = (flags & 4) ? 1e30f : 20.0f;
  sensor_msgs::PointCloud2 msg;
  msg.is_bigendian = flags & 1;
  msg.is_dense = flags & 2;
  const int num_fields = r.u8() % 9;
  for (int i = 0; i < num_fields; ++i) {
    sensor_msgs::PointField field;
    field.name = kNames[r.u8() % (sizeof(kNames) / sizeof(kNames[0]))];
    field.offset = r.u8();
    field.datatype = r.u8() % 10;
    field.count = r.u8() % 32;
    msg.fields.push_back(field);
  }
  msg.height = r.u8() % 4;
  msg.width = r.u16() % 512;
  msg.point_step = r.u8();
  msg.row_step = r.u16();
  msg.data.assign(data + std::min(r.at, size), data + size);

  SemanticCloud cloud;
  const std::string error = fromPointCloud2(msg, options, &cloud);
  if (!error.empty()) return 0;
  const size_t n = cloud.points_S.size();
  const size_t C = static_cast<size_t>(options.num_classes);
  if (cloud.evidence.size() != n * C) fuzz::fuzzFail("evidence is not points x C");
  for (size_t i = 0; i < n; ++i) {
    const octomap::point3d& p = cloud.points_S.getPoint(i);
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
      fuzz::fuzzFail("a non-finite point was returned");
    }
  }
  for (float e : cloud.evidence) {
    if (!std::isfinite(e) || e < 0.0f) fuzz::fuzzFail("invalid evidence returned as valid");
  }
  if (n > 0 && n <= 64) {  // and the map takes it
    EvidentialOcTree tree(0.2, options.num_classes);
    SemanticConfig config;
    config.threads = 1;
    // Parsed points may lie kilometres away; their rays are the integrator's cost (the .ot
    // target inserts scans); here they more than doubled the time of each input.
    config.max_range = 20.0;
    tree.setConfig(config);
    try {
      tree.insertSemanticScan(cloud.points_S, cloud.evidence, octomap::point3d(0.f, 0.f, 0.f));
    } catch (const std::invalid_argument& e) {
      fuzz::fuzzFail(std::string("a parsed cloud is refused by the map: ") + e.what());
    }
  }
  return 0;
}
