// Issue 16 item 3 before/after: clearBox with a NaN corner on a map of a wall
// (docs/experiments/reliability.md).
#include <cmath>
#include <iostream>
#include <stdexcept>

#ifdef OLD_WRITERS
#include "map_editing.h"  // src/ros/map_editing.h before the fix
#else
#include "evidential_octomap/map_editing.h"
#endif

using namespace evidential_octomap;

int main() {
  const float nan = std::nanf("");
  const octomap::point3d boxes[][2] = {{{4.f, -3.f, -1.f}, {nan, nan, nan}},
                                       {{-1000.f, -1000.f, -1000.f}, {nan, 1000.f, 1000.f}}};
  for (const auto& box : boxes) {
    EvidentialOcTree tree(0.2, 3);
    octomap::Pointcloud pts;
    std::vector<float> ev;
    for (float y = -2.f; y <= 2.f; y += 0.05f)
      for (float z = 0.f; z <= 1.5f; z += 0.05f) {
        pts.push_back(5.05f, y, z);
        ev.insert(ev.end(), {0.f, 30.f, 0.f});
      }
    tree.insertSemanticScan(pts, ev, octomap::point3d(1.f, 0.f, 0.f));
    const size_t before = tree.numSemanticNodes(), leaves = tree.getNumLeafNodes();
    std::string outcome;
    try {
      const uint32_t cleared = clearBox(&tree, box[0], box[1]);
      outcome = "cleared " + std::to_string(cleared) + " leaves";
    } catch (const std::invalid_argument& e) {
      outcome = std::string("refused: ") + e.what();
    }
    std::cout << "clear_bbx " << box[0] << " .. " << box[1] << " on " << leaves << " leaves ("
              << before << " semantic): " << outcome << "; semantic leaves after "
              << tree.numSemanticNodes() << "\n";
  }
}
