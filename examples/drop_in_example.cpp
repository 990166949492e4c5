// Drop-in use of evidential_octomap: the tree is an OctoMap occupancy tree that also fuses
// per-point semantic evidence (e.g. from an evidential segmentation network).
//   example_drop_in [out.ot]
#include <evidential_octomap/evidential_octomap.h>  // the whole map library, and OctoMap

#include <iostream>
#include <memory>
#include <vector>

int main(int argc, char** argv) {
  using evidential_octomap::EvidentialOcTree;
  const int num_classes = 2;  // 0 = ground, 1 = obstacle
  EvidentialOcTree tree(0.2, num_classes);
  tree.setClassNames({"ground", "obstacle"});

  // One synthetic scan from a sensor 1.5 m above a flat ground: a row of ground points and a
  // small wall, each point with its evidence vector (N x C, row-major).
  const octomap::point3d origin_W(0.0f, 0.0f, 1.5f);
  octomap::Pointcloud points_W;
  std::vector<float> evidence;
  for (float y = -1.0f; y <= 1.0f; y += 0.1f) {
    points_W.push_back(2.0f, y, 0.0f);
    evidence.insert(evidence.end(), {8.0f, 0.5f});
    points_W.push_back(4.0f, y, 1.0f);
    evidence.insert(evidence.end(), {0.5f, 8.0f});
  }
  const auto stats = tree.insertSemanticScan(points_W, evidence, origin_W);

  // Semantic queries ...
  const auto wall = tree.query(octomap::point3d(4.0f, 0.0f, 1.0f));
  std::cout << "wall voxel: class " << tree.classNames()[wall.label] << ", uncertainty "
            << wall.uncertainty << " (" << stats.voxels_updated << " voxels updated)\n";
  // ... and the whole OctoMap API still works.
  const octomap::point3d ground_voxel =
      tree.keyToCoord(tree.coordToKey(octomap::point3d(2.0f, 0.0f, 0.0f)));
  octomap::point3d hit;
  const bool found = tree.castRay(origin_W, ground_voxel - origin_W, hit,
                                  /*ignoreUnknownCells=*/true) &&
                     hit.distance(ground_voxel) < tree.getResolution();
  std::cout << "ray hit: " << found << " at " << hit << "\n";

  // .ot files come back as our tree through OctoMap's generic reader.
  const char* path = argc > 1 ? argv[1] : "drop_in_example.ot";
  tree.write(path);
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(path));
  auto* read_back = dynamic_cast<EvidentialOcTree*>(any.get());
  const bool ok = read_back && wall.label == 1 && found &&
                  read_back->query(octomap::point3d(4.0f, 0.0f, 1.0f)).label == 1;
  std::cout << (ok ? "ok" : "FAILED") << "\n";
  return ok ? 0 : 1;
}
