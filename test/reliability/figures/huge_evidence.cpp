// Issue 16 item 1 before/after: two points with evidence 3e38 (finite) in one down-sampling
// cell; what the voxel answers, whether the map saves, and whether the file loads.
#include <cmath>
#include <iostream>

#include "evidential_octomap/io.h"

using namespace evidential_octomap;

int main() {
  EvidentialOcTree tree(0.2, 3);
  octomap::Pointcloud points;
  points.push_back(2.101f, 1.001f, 0.501f);
  points.push_back(2.102f, 1.002f, 0.502f);
  tree.insertSemanticScan(points, {3e38f, 0.f, 0.f, 3e38f, 0.f, 0.f}, octomap::point3d(0, 0, 0.5f));
  const std::vector<float> payload = tree.payload(tree.search(octomap::point3d(2.1f, 1.0f, 0.5f)));
  std::cout << "huge evidence: payload " << (payload.empty() ? -1.f : payload[0]) << ", label "
            << tree.query(octomap::point3d(2.1f, 1.0f, 0.5f)).label;
  try {
    saveMap(tree, "huge.ot");
    std::cout << ", saved";
    loadMap("huge.ot");
    std::cout << ", loaded\n";
  } catch (const std::exception& e) {
    std::cout << ", " << e.what() << "\n";
  }
}
