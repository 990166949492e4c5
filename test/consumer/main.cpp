// Consumer of the installed library: insert a tiny scan, write an .ot, read it back through
// OctoMap's generic reader and check that the tree type survives. Exit code 0 = success.
#include <evidential_octomap/evidential_octomap.h>  // the whole map library, and OctoMap

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "consumer_map.ot";
  const int num_classes = 3;
  evidential_octomap::EvidentialOcTree tree(0.2, num_classes);

  octomap::Pointcloud points_W;
  std::vector<float> evidence;
  for (int i = 0; i < 10; ++i) {
    points_W.push_back(2.0f, -0.5f + 0.1f * i, 0.0f);
    evidence.insert(evidence.end(), {0.0f, 5.0f, 0.0f});  // class 1
  }
  tree.insertSemanticScan(points_W, evidence, octomap::point3d(0, 0, 0));
  if (tree.numSemanticNodes() == 0) {
    std::cerr << "no semantic voxels after insertion\n";
    return 1;
  }
  const auto before = tree.query(octomap::point3d(2.0f, 0.0f, 0.0f));
  if (before.label != 1) {
    std::cerr << "expected class 1 at the scan, got " << before.label << "\n";
    return 1;
  }
  if (!tree.write(path)) {
    std::cerr << "write failed: " << path << "\n";
    return 1;
  }

  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(path));
  if (!any) {
    std::cerr << "AbstractOcTree::read returned null\n";
    return 1;
  }
  if (any->getTreeType() != "EvidentialOcTree") {
    std::cerr << "wrong tree type: " << any->getTreeType() << "\n";
    return 1;
  }
  auto* read_back = dynamic_cast<evidential_octomap::EvidentialOcTree*>(any.get());
  if (!read_back || read_back->numClasses() != num_classes ||
      read_back->query(octomap::point3d(2.0f, 0.0f, 0.0f)).label != 1) {
    std::cerr << "read-back tree differs\n";
    return 1;
  }
  std::cout << "consumer ok: " << read_back->size() << " nodes, " << read_back->numSemanticNodes()
            << " semantic\n";
  return 0;
}
