// Opens a map file exactly as octovis 1.9 does (ViewerGui::openFile: `.bt` through
// OcTree::readBinary, anything else through AbstractOcTree::read), in a program that links only
// the stock OctoMap library, as octovis does, and never this project's. Prints
//     <tree type> <leaves> <occupied leaves>
// and exits 0, or prints why it could not open the file and exits 1 (octovis then shows "Cannot
// open OcTree file"). Used by test_ot_file's StockTools tests: octovis itself needs a display.
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <iostream>
#include <memory>
#include <string>

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Counts leaves at the finest depth (expanded), so pruning does not change the numbers.
template <class Tree>
void printLeaves(Tree& tree) {
  tree.expand();
  size_t leaves = 0, occupied = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    ++leaves;
    if (tree.isNodeOccupied(*it)) ++occupied;
  }
  std::cout << tree.getTreeType() << " " << leaves << " " << occupied << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: stock_octomap_open <map.bt|map.ot>\n";
    return 2;
  }
  const std::string path = argv[1];
  if (endsWith(path, ".bt")) {
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(path)) {
      std::cout << "refused: not a binary OcTree\n";
      return 1;
    }
    printLeaves(tree);
    return 0;
  }
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(path));
  if (!tree) {
    std::cout << "refused: AbstractOcTree::read returned no tree\n";
    return 1;
  }
  if (auto* occupancy = dynamic_cast<octomap::OcTree*>(tree.get())) {
    printLeaves(*occupancy);
  } else if (auto* color = dynamic_cast<octomap::ColorOcTree*>(tree.get())) {
    printLeaves(*color);
  } else {
    std::cout << tree->getTreeType() << " (not drawn)\n";
  }
  return 0;
}
