// `evidential_octomap info map.ot`: what a saved map holds.
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "evidential_octomap/io.h"

namespace evidential_octomap::tools {

namespace {
void runInfo(const std::string& path) {
  const std::unique_ptr<EvidentialOcTree> tree = loadMap(path);
  size_t leaves = 0, occupied = 0, free_leaves = 0, semantic_leaves = 0;
  std::vector<size_t> per_class(tree->numClasses(), 0);
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    ++leaves;
    (tree->isNodeOccupied(*it) ? occupied : free_leaves)++;
    if (it->hasSemantics()) {
      ++semantic_leaves;
      const int label = tree->opinion(&*it).label;
      if (label >= 0 && label < tree->numClasses()) ++per_class[label];
    }
  }
  double x, y, z, X, Y, Z;
  tree->getMetricMin(x, y, z);
  tree->getMetricMax(X, Y, Z);
  std::cout << "file:            " << path << "\n"
            << "type:            " << tree->getTreeType() << "\n"
            << "resolution:      " << tree->getResolution() << " m\n"
            << "classes (C):     " << tree->numClasses() << "\n"
            << "rule:            " << tree->rule().name()
            << (tree->rule().uncertaintyIsMass() ? " (vacuity u: a mass in [0,1])"
                                                 : " (uncertainty: Dirichlet variance)")
            << "\n"
            << "nodes:           " << tree->size() << " (" << leaves << " leaves: " << occupied
            << " occupied, " << free_leaves << " free)\n"
            << "semantic nodes:  " << tree->numSemanticNodes() << " (" << semantic_leaves
            << " leaves)\n"
            << "memory:          " << tree->memoryUsage() << " B ("
            << std::fixed << std::setprecision(1) << tree->memoryUsage() / 1048576.0 << " MiB)\n"
            << "bounds [m]:      (" << x << ", " << y << ", " << z << ") .. (" << X << ", " << Y
            << ", " << Z << ")\n" << std::defaultfloat << std::setprecision(6)
            << "parameters:\n";
  std::ostringstream params;
  tree->config().print(params);
  std::istringstream lines(params.str());
  for (std::string line; std::getline(lines, line);) std::cout << "  " << line << "\n";
  if (tree->config().rule == "dempster") {
    std::cout << "read-out cap:    " << tree->effectiveEvidenceCap()
              << (tree->config().evidence_cap == SemanticConfig::kAdaptiveCap ? " (adaptive" : " (fixed")
              << "; mean point log-evidence m = " << tree->meanPointLogEvidence() << ")\n";
  }
  std::cout << "classes (leaves labelled):\n";
  for (int c = 0; c < tree->numClasses(); ++c) {
    std::cout << "  " << std::setw(3) << c << " " << std::left << std::setw(16)
              << tree->classNames()[c] << std::right << " " << per_class[c] << "\n";
  }
}
}  // namespace

void addInfoCommand(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "info", "Print what a saved .ot holds: type, resolution, C, class names, rule, parameters, "
              "node counts, semantic nodes, memory");
  cmd->add_option("map", *path, "Map file (.ot)")->required()->check(CLI::ExistingFile);
  cmd->callback([path]() { runInfo(*path); });
}

}  // namespace evidential_octomap::tools
