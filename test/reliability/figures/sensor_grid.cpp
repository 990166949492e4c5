// Issue 16 item 2 before/after: sensor models set through OctoMap's setters on a small map,
// then saved and loaded back. Counts maps written but unloadable, refused, and round-tripped.
#include <iostream>

#include "evidential_octomap/io.h"

using namespace evidential_octomap;

int main() {
  int unloadable = 0, refused = 0, loaded = 0;
  for (double hit : {0.7, 0.999, 1.0})
    for (double miss : {0.0, 0.001, 0.4})
      for (double lo : {0.0, 0.12})
        for (double hi : {0.97, 1.0}) {
          EvidentialOcTree tree(0.2, 2);
          tree.setProbHit(hit);
          tree.setProbMiss(miss);
          tree.setClampingThresMin(lo);
          tree.setClampingThresMax(hi);
          try {
            octomap::Pointcloud points;
            points.push_back(1.f, 0.2f, 0.f);
            points.push_back(1.4f, 0.2f, 0.f);
            tree.insertSemanticScan(points, {7.f, 0.5f, 0.5f, 7.f}, octomap::point3d(0, 0, 0.5f));
            saveMap(tree, "sensor.ot");
          } catch (const std::exception& e) {
            ++refused;
            continue;
          }
          try {
            loadMap("sensor.ot");
            ++loaded;
          } catch (const std::exception& e) {
            ++unloadable;
          }
        }
  std::cout << "sensor models (36, 32 with a probability at 0 or 1): " << unloadable
            << " saved but unloadable, " << refused << " refused, " << loaded << " loaded\n";
}
