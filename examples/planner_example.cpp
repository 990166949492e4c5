// A planner's side of a map: load an .ot safely, ask class, belief and error probability at
// points and along a ray, and keep going when a file is refused.
//   planner_example map.ot [x y z]...        every point is queried; the first two also as a ray
// Exit code 0: map loaded and queried; 2: the map was refused (the planner keeps its last map).
#include <evidential_octomap/evidential_octree.h>
#include <evidential_octomap/io.h>

#include <cstdlib>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using evidential_octomap::EvidentialOcTree;

// A label is trusted below this error probability (the probability that it is wrong). The cut-off
// recommended by docs/experiments/cutoff.md, where its measured error rate is.
constexpr float kMaxErrorProbability = 0.2f;

// What a planner wants to know about one place: occupied? which class, how sure?
void describe(const EvidentialOcTree& map, const octomap::point3d& p) {
  const octomap::OcTreeNode* node = map.search(p);
  std::cout << "at (" << p.x() << ", " << p.y() << ", " << p.z() << "): ";
  if (!node) {
    std::cout << "unknown\n";
    return;
  }
  const auto opinion = map.query(p);
  std::cout << (map.isNodeOccupied(node) ? "occupied" : "free");
  if (opinion.label < 0) {
    std::cout << ", no semantic evidence\n";
    return;
  }
  // The error probability: how likely the label is wrong (the calibration's error model when one
  // is applied, else 1 - max p). belief[c]: the mass committed to class c; the vacuity u: how
  // little evidence the voxel holds, which never reaches 0 and does not say whether it is right.
  std::cout << ", class " << map.classNames()[opinion.label] << ", belief "
            << opinion.belief[opinion.label] << ", error probability "
            << map.rule().errorProbability(opinion) << ", vacuity u " << opinion.uncertainty
            << ", conflict " << opinion.conflict << "\n";
}

// Walks the voxels from `from` to `to` to the first occupied one, and says whether its class can
// be trusted (error probability below kMaxErrorProbability), as a planner deciding to drive over
// or around it.
void walkRay(const EvidentialOcTree& map, const octomap::point3d& from,
             const octomap::point3d& to) {
  octomap::KeyRay keys;
  if (!map.computeRayKeys(from, to, keys)) {
    std::cout << "ray: leaves the map's key range\n";
    return;
  }
  keys.addKey(map.coordToKey(to));  // computeRayKeys stops before the end voxel
  int unknown = 0;
  for (const octomap::OcTreeKey& key : keys) {
    const octomap::OcTreeNode* node = map.search(key);
    if (!node) {
      ++unknown;
      continue;
    }
    if (!map.isNodeOccupied(node)) continue;
    const auto opinion = map.query(key);
    const octomap::point3d c = map.keyToCoord(key);
    std::cout << "ray: stops at (" << c.x() << ", " << c.y() << ", " << c.z() << "), occupied";
    if (opinion.label < 0)
      std::cout << ", no semantic evidence";
    else {
      const float p_wrong = map.rule().errorProbability(opinion);
      std::cout << ", class " << map.classNames()[opinion.label] << ", error probability "
                << p_wrong << (p_wrong < kMaxErrorProbability ? " (trusted)" : " (not trusted)");
    }
    std::cout << "; " << unknown << " unknown voxels before it\n";
    return;
  }
  std::cout << "ray: no occupied voxel over " << keys.size() << " voxels (" << unknown
            << " unknown)\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || (argc - 2) % 3 != 0) {
    std::cerr << "usage: planner_example map.ot [x y z]...\n";
    return 1;
  }
  std::unique_ptr<EvidentialOcTree> map;
  try {
    // loadMap checks the file: type, size limit (here 2 GB), checksum, invariants. Never
    // AbstractOcTree::read for files from elsewhere: it returns an empty tree on corrupt data.
    map = evidential_octomap::loadMap(argv[1], uint64_t(2) << 30);
  } catch (const std::runtime_error& e) {
    std::cerr << "map refused: " << e.what() << "\n";
    return 2;  // a planner would keep the map it has and say so
  }
  std::cout << "map: " << map->getNumLeafNodes() << " leaves, resolution "
            << map->getResolution() << " m, " << map->numClasses() << " classes\n";

  std::vector<octomap::point3d> points;
  for (int i = 2; i + 2 < argc; i += 3)
    points.emplace_back(std::atof(argv[i]), std::atof(argv[i + 1]), std::atof(argv[i + 2]));
  for (const auto& p : points) describe(*map, p);
  if (points.size() >= 2) walkRay(*map, points[0], points[1]);
  return 0;
}
