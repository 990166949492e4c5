// Small maps and class tables shared by the ROS layer's roscore-free tests.
#pragma once

#include <memory>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"

namespace ros_test {

// Four classes: 0 road, 1 building, 2 vegetation, 3 pole, with distinct colours.
inline evidential_octomap::ClassTable fourClasses() {
  evidential_octomap::ClassTable t;
  t.dataset = "test";
  t.names = {"road", "building", "vegetation", "pole"};
  t.colors = {{{128, 64, 128}}, {{255, 200, 0}}, {{0, 175, 0}}, {{255, 240, 150}}};
  return t;
}

// Seen from the origin: a road patch (class 0) at z = -1.05 for x in [1, 3.9], and a wall
// (class 1) at x = 4.05 for y in [-1, 1], z in [-1, 1]; one-hot evidence of 30.
inline std::unique_ptr<evidential_octomap::EvidentialOcTree> roadAndWall() {
  auto tree = std::make_unique<evidential_octomap::EvidentialOcTree>(0.2, 4);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  auto add = [&](float x, float y, float z, int cls) {
    points.push_back(x, y, z);
    for (int c = 0; c < 4; ++c) evidence.push_back(c == cls ? 30.f : 0.f);
  };
  for (float x = 1.f; x <= 3.9f; x += 0.1f)
    for (float y = -1.f; y <= 1.f; y += 0.1f) add(x, y, -1.05f, 0);
  for (float y = -1.f; y <= 1.f; y += 0.1f)
    for (float z = -1.f; z <= 1.f; z += 0.1f) add(4.05f, y, z, 1);
  tree->insertSemanticScan(points, evidence, octomap::point3d(0, 0, 0));
  return tree;
}

}  // namespace ros_test
