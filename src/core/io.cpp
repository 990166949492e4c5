#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/io.h"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <octomap/AbstractOcTree.h>
#include <octomap/AbstractOccupancyOcTree.h>

namespace evidential_octomap {

void saveMap(const EvidentialOcTree& tree, const std::string& path) {
  const std::string problem = tree.parameterProblem();
  if (!problem.empty()) throw std::runtime_error("cannot save " + path + ": " + problem);
  writeFileAtomically(path, [&](std::ostream& s) {
    s << std::setprecision(17);  // AbstractOcTree::write prints `res` with the stream's precision
    return tree.write(s) && s.good();
  });
}

namespace {
// OctoMap's own file headers: first lines and the header parser are protected in
// AbstractOcTree / AbstractOccupancyOcTree, so they are reached through a subclass.
struct OctomapHeader : octomap::AbstractOccupancyOcTree {
  static const std::string& btFirstLine() { return binaryFileHeader; }
  // Reads a first line starting with `first_line`, then the header up to "data".
  static bool read(std::istream& s, const std::string& first_line, std::string& id,
                   unsigned& size, double& res) {
    std::string line;
    std::getline(s, line);
    if (line.compare(0, first_line.length(), first_line) != 0) return false;
    return readHeader(s, id, size, res);
  }
  static bool readOt(std::istream& s, std::string& id, unsigned& size, double& res) {
    return read(s, fileHeader, id, size, res);
  }
  static bool readBt(std::istream& s, std::string& id, unsigned& size, double& res) {
    return read(s, binaryFileHeader, id, size, res);
  }
};
}  // namespace

bool writeBinaryOccupancy(const EvidentialOcTree& tree, std::ostream& s) {
  // As AbstractOccupancyOcTree::writeBinaryConst, but under the plain OcTree's id.
  s << OctomapHeader::btFirstLine() << "\n"
    << "# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
    << "id OcTree\n"
    << "size " << tree.size() << "\n"
    << "res " << std::setprecision(17) << tree.getResolution() << "\n"
    << "data\n";
  return tree.writeBinaryData(s) && s.good();
}

void saveBinaryOccupancy(const EvidentialOcTree& tree, const std::string& path) {
  writeFileAtomically(path, [&](std::ostream& s) { return writeBinaryOccupancy(tree, s); });
}

namespace {
// Opens a regular file for reading, checked before opening: opening a FIFO blocks until a writer
// appears, and a device such as /dev/zero never ends. max_bytes 0: no size limit.
std::ifstream openRegularFile(const std::string& path, uint64_t max_bytes) {
  struct stat info;
  if (::stat(path.c_str(), &info) != 0) {
    throw std::runtime_error("cannot open " + path + ": " + std::strerror(errno));
  }
  if (!S_ISREG(info.st_mode)) {
    throw std::runtime_error(path + " is not a regular file (a FIFO, device or directory)");
  }
  if (max_bytes > 0 && uint64_t(info.st_size) > max_bytes) {
    throw std::runtime_error(path + " has " + std::to_string(info.st_size) +
                             " bytes, more than the limit of " + std::to_string(max_bytes));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path + ": " + std::strerror(errno));
  return in;
}
}  // namespace

std::unique_ptr<EvidentialOcTree> loadBinaryOccupancy(const std::string& path, int num_classes,
                                                      const SemanticConfig& config) {
  std::ifstream in = openRegularFile(path, 0);
  std::string id;
  unsigned size = 0;
  double res = 0.0;
  if (!OctomapHeader::readBt(in, id, size, res)) {
    throw std::runtime_error(path + " is not an OctoMap binary (.bt) file");
  }
  if (!std::isfinite(res) || !(res > 0.0)) {
    throw std::runtime_error(path + ": resolution " + std::to_string(res) + " is not > 0");
  }
  // Every occupancy tree (OcTree, ColorOcTree, ours) writes the same binary data.
  auto tree = std::make_unique<EvidentialOcTree>(res, num_classes, config);
  if (size > 0) {
    tree->readBinaryData(in);
    if (in.fail()) throw std::runtime_error(path + ": truncated or corrupt data");
    detail::TreeEditing::updateInnerNodes(*tree);
  }
  return tree;
}

std::unique_ptr<EvidentialOcTree> loadMap(const std::string& path, uint64_t max_bytes) {
  std::ifstream in = openRegularFile(path, max_bytes);
  return loadMap(in, path);
}

std::unique_ptr<EvidentialOcTree> loadMap(std::istream& in, const std::string& path) {
  // The header is checked before any data is read: data of other tree types never reaches
  // OctoMap's readers (which trust their input: no depth limit), and our data is read even when
  // `size` is 0, because an empty map still carries its semantic header (C, names, rule).
  std::string id;
  unsigned size = 0;
  double res = 0.0;
  if (!OctomapHeader::readOt(in, id, size, res)) {
    throw std::runtime_error(path + " is not a readable OctoMap .ot file");
  }
  if (id != "EvidentialOcTree") {
    throw std::runtime_error(path + " holds a " + id + ", not an EvidentialOcTree");
  }
  if (!std::isfinite(res) || !(res > 0.0)) {
    throw std::runtime_error(path + ": resolution " + std::to_string(res) + " is not > 0");
  }
  auto tree = std::make_unique<EvidentialOcTree>(res);
  tree->readData(in);
  if (!tree->readError().empty()) throw std::runtime_error(path + ": " + tree->readError());
  if (in.fail()) throw std::runtime_error(path + ": truncated or corrupt data");
  return tree;
}

std::string readProblem(const octomap::AbstractOcTree* tree) {
  if (!tree) return "no tree: the file is missing, not an OctoMap file, or of an unknown type";
  const auto* ours = dynamic_cast<const EvidentialOcTree*>(tree);
  if (!ours) return "the file holds a " + tree->getTreeType() + ", not an EvidentialOcTree";
  if (!ours->readError().empty()) return ours->readError();
  if (ours->dataSectionSkipped()) {
    return "OctoMap skipped the data section (header says size 0): class names, rule and "
           "parameters are defaults; read the file with evidential_octomap::loadMap";
  }
  return "";
}

ClassTable::Rgb uncertaintyColor(double t) {
  // A perceptually ordered blue -> cyan -> yellow -> red ramp (certain ... uncertain).
  t = std::isfinite(t) ? std::min(std::max(t, 0.0), 1.0) : 1.0;
  static const double stops[5][3] = {
      {48, 18, 59}, {40, 150, 230}, {90, 230, 120}, {250, 200, 40}, {180, 20, 10}};
  const double x = t * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  ClassTable::Rgb rgb;
  for (int c = 0; c < 3; ++c) {
    rgb[c] = static_cast<uint8_t>(std::lround(stops[i][c] * (1.0 - f) + stops[i + 1][c] * f));
  }
  return rgb;
}

ColorMode colorModeFromName(const std::string& name) {
  if (name == "class") return ColorMode::kClass;
  if (name == "uncertainty") return ColorMode::kUncertainty;
  if (name == "vacuity") return ColorMode::kVacuity;
  throw std::invalid_argument("colours must be 'class', 'uncertainty' (P(label wrong)) or "
                              "'vacuity', not '" + name + "'");
}

std::unique_ptr<octomap::ColorOcTree> toColorOcTree(const EvidentialOcTree& tree,
                                                    const ClassTable& classes, ColorMode mode) {
  if (classes.numClasses() != tree.numClasses()) {
    throw std::invalid_argument("class table has " + std::to_string(classes.numClasses()) +
                                " classes, the map " + std::to_string(tree.numClasses()));
  }
  // The vacuity of Dirichlet rules is a variance: scaled by the map's largest value.
  float max_uncertainty = 1.0f;
  if (mode == ColorMode::kVacuity && !tree.rule().uncertaintyIsMass()) {
    max_uncertainty = 0.0f;
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
      if (it->hasSemantics()) {
        max_uncertainty = std::max(max_uncertainty, tree.opinion(&*it).uncertainty);
      }
    }
    if (!(max_uncertainty > 0.0f)) max_uncertainty = 1.0f;
  }
  const float max_error = 1.0f - 1.0f / float(tree.numClasses());  // every class alike
  // Same node structure as the source (pruned blocks stay blocks): serialise it in
  // ColorOcTree's own data format and let ColorOcTree read it.
  std::stringstream data;
  std::function<void(const EvidentialOcTreeNode*)> writeNode = [&](const EvidentialOcTreeNode* node) {
    ClassTable::Rgb rgb{128, 128, 128};  // no semantic evidence, or no class answered
    if (node->hasSemantics()) {
      const VoxelOpinion o = tree.opinion(node);
      if (mode == ColorMode::kClass && o.label >= 0) rgb = classes.colors[o.label];
      if (mode == ColorMode::kVacuity) rgb = uncertaintyColor(o.uncertainty / max_uncertainty);
      if (mode == ColorMode::kUncertainty && o.label >= 0)  // P(label wrong) needs a label
        rgb = uncertaintyColor(tree.rule().errorProbability(o) / max_error);
    }
    const float value = node->getValue();
    data.write(reinterpret_cast<const char*>(&value), sizeof(value));
    data.write(reinterpret_cast<const char*>(rgb.data()), 3);
    uint8_t children = 0;
    for (unsigned i = 0; i < 8; ++i) {
      if (tree.nodeChildExists(node, i)) children |= static_cast<uint8_t>(1u << i);
    }
    data.write(reinterpret_cast<const char*>(&children), 1);
    for (unsigned i = 0; i < 8; ++i) {
      if (children & (1u << i)) writeNode(tree.getNodeChild(node, i));
    }
  };
  auto color_tree = std::make_unique<octomap::ColorOcTree>(tree.getResolution());
  color_tree->setClampingThresMin(tree.getClampingThresMin());
  color_tree->setClampingThresMax(tree.getClampingThresMax());
  color_tree->setProbHit(tree.getProbHit());
  color_tree->setProbMiss(tree.getProbMiss());
  color_tree->setOccupancyThres(tree.getOccupancyThres());
  if (tree.getRoot()) {
    writeNode(tree.getRoot());
    color_tree->readData(data);
  }
  return color_tree;
}

}  // namespace evidential_octomap
