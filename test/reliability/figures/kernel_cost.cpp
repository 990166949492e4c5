// Issue 16 item 4 before/after: the kernel setting l = 5 m, beta = 10 at 0.2 m on a 16-point
// scan; the figure is whether the insert is refused or how long it takes (run it under timeout).
#include <ctime>
#include <iostream>

#include "evidential_octomap/evidential_octree.h"

using namespace evidential_octomap;

int main() {
  SemanticConfig config;
  config.length_scale = 5.0;
  config.beta = 10.0;
  std::string outcome;
  try {
    EvidentialOcTree tree(0.2, 3, config);
    octomap::Pointcloud points;
    std::vector<float> evidence;
    for (int i = 0; i < 16; ++i) {
      points.push_back(3.f + 0.3f * i, 0.5f, 0.2f);
      evidence.insert(evidence.end(), {5.f, 1.f, 1.f});
    }
    tree.insertSemanticScan(points, evidence, octomap::point3d(0, 0, 0.5f));
    outcome = "inserted, " + std::to_string(tree.getNumLeafNodes()) + " leaves";
  } catch (const std::exception& e) {
    outcome = std::string("refused: ") + e.what();
  }
  std::cout << "kernel l=5 beta=10: " << outcome << " after "
            << double(std::clock()) / CLOCKS_PER_SEC << " s CPU\n";
}
