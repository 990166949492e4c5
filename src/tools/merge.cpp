// `evidential_octomap merge a.ot b.ot -o ab.ot`: fuse two maps (EvidentialOcTree::merge).
#include <iostream>
#include <memory>

#include "commands.h"
#include "evidential_octomap/io.h"

namespace evidential_octomap::tools {

namespace {
struct MergeOptions {
  std::vector<std::string> inputs;
  std::string output;
};

void runMerge(const MergeOptions& o) {
  std::unique_ptr<EvidentialOcTree> result = loadMap(o.inputs.at(0));
  for (size_t i = 1; i < o.inputs.size(); ++i) {
    const std::unique_ptr<EvidentialOcTree> other = loadMap(o.inputs[i]);
    try {
      result->merge(*other);
    } catch (const std::exception& e) {
      throw std::runtime_error("cannot merge " + o.inputs[i] + " into " + o.inputs[0] + ": " +
                               e.what());
    }
  }
  saveMap(*result, o.output);
  std::cout << "merged " << o.inputs.size() << " maps into " << o.output << " ("
            << result->getNumLeafNodes() << " leaves, " << result->numSemanticNodes()
            << " semantic nodes)\n";
}
}  // namespace

void addMergeCommand(CLI::App& app) {
  auto o = std::make_shared<MergeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "merge", "Fuse maps of equal resolution, C and rule: occupancy log-odds add (clamped), "
               "semantic payloads add (Dempster's rule in evidence space)");
  cmd->add_option("maps", o->inputs, "Two or more .ot maps")
      ->required()
      ->expected(2, -1)
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->output, "Merged map (.ot)")->required();
  cmd->callback([o]() { runMerge(*o); });
}

}  // namespace evidential_octomap::tools
