// libFuzzer target: the node's service handlers as MappingServer calls them (src/ros/
// map_services.cpp: answerQuery for ~query, clearBoxRequest for ~clear_bbx), on requests decoded
// from the bytes (every coordinate may be NaN, inf or huge). Needs the generated service headers:
// built with -DEVIDENTIAL_FUZZ_ROS=ON like fuzz_pointcloud2 (see fuzz/CMakeLists.txt).
// Invariants: a response per point, unknown (-1) for non-finite points, every readout an
// opinion; a refused box (success false) leaves the map byte-identical.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>

#include "fuzz_targets.h"
#include "map_services.h"

namespace {

using namespace evidential_octomap;

struct Reader {
  const uint8_t* data;
  size_t size, at = 0;
  bool done() const { return at >= size; }
  double number() {
    double value = 0.0;
    uint8_t bytes[8] = {0};
    for (uint8_t& b : bytes) b = at < size ? data[at++] : 0;
    std::memcpy(&value, bytes, 8);
    return value;
  }
  geometry_msgs::Point point() {
    geometry_msgs::Point p;
    p.x = number();
    p.y = number();
    p.z = number();
    return p;
  }
};

const EvidentialOcTree& baseMap() {
  static EvidentialOcTree* tree = [] {
    auto* t = new EvidentialOcTree(0.2, 3);
    octomap::Pointcloud points;
    std::vector<float> evidence;
    for (float y = -1.f; y <= 1.f; y += 0.2f) {
      points.push_back(3.f, y, 0.f);
      evidence.insert(evidence.end(), {9.f, 1.f, 0.f});
    }
    t->insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.f));
    return t;
  }();
  return *tree;
}

std::string bytesOf(const EvidentialOcTree& tree) {
  std::ostringstream out;
  tree.write(out);
  return out.str();
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::silenceDiagnostics();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  EvidentialOcTree tree(baseMap());
  Reader in{data, size};
  while (!in.done()) {
    if (in.data[in.at++] % 2 == 0) {
      QueryMap::Request req;
      QueryMap::Response res;
      for (int i = 0; i < 4 && !in.done(); ++i) req.points.push_back(in.point());
      answerQuery(tree, req, &res);
      const size_t n = req.points.size(), C = size_t(tree.numClasses());
      if (res.labels.size() != n || res.occupancy.size() != n || res.beliefs.size() != n * C) {
        fuzz::fuzzFail("~query: not one answer per point");
      }
      for (size_t i = 0; i < n; ++i) {
        const auto& p = req.points[i];
        const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
        if (!finite && (res.labels[i] != -1 || res.occupancy[i] != -1.f)) {
          fuzz::fuzzFail("~query: a non-finite point has an answer");
        }
        if (!std::isfinite(res.uncertainties[i])) fuzz::fuzzFail("~query: u not finite");
      }
    } else {
      ClearBbx::Request req;
      ClearBbx::Response res;
      req.min = in.point();
      req.max = in.point();
      const std::string before = bytesOf(tree);
      clearBoxRequest(&tree, req, &res);
      if (!res.success && bytesOf(tree) != before) {
        fuzz::fuzzFail("~clear_bbx: a refused box changed the map");
      }
      if (!res.success && res.message.empty()) fuzz::fuzzFail("~clear_bbx: refused silently");
    }
  }
  return 0;
}
