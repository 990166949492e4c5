// `evidential_octomap export`: ColorOcTree (class, uncertainty or vacuity colours) for octovis
// and other stock OctoMap tools, and the occupancy-only .bt.
#include <cmath>
#include <iostream>
#include <memory>

#include "commands.h"
#include "evidential_octomap/io.h"

namespace evidential_octomap::tools {

namespace {
struct ExportOptions {
  std::string map, classes, color_octree, binary, mode = "class";
  std::shared_ptr<const Calibration> calibration;
};

// A table with the map's own class names and a fixed distinct palette, for maps whose class
// table file is not at hand.
ClassTable defaultTable(const EvidentialOcTree& tree) {
  ClassTable t;
  t.dataset = "from-map";
  t.names = tree.classNames();
  for (int c = 0; c < tree.numClasses(); ++c) {
    const double h = std::fmod(c * 0.618033988749895, 1.0) * 6.0;  // golden-ratio hues
    const int i = int(h);
    const double f = h - i;
    const double v[6][3] = {{1, f, 0}, {1 - f, 1, 0}, {0, 1, f},
                            {0, 1 - f, 1}, {f, 0, 1}, {1, 0, 1 - f}};
    t.colors.push_back({uint8_t(40 + 200 * v[i][0]), uint8_t(40 + 200 * v[i][1]),
                        uint8_t(40 + 200 * v[i][2])});
  }
  return t;
}

void runExport(const ExportOptions& o) {
  if (o.color_octree.empty() && o.binary.empty()) {
    throw std::runtime_error("nothing to export: give --color-octree and/or --binary");
  }
  const std::unique_ptr<EvidentialOcTree> tree = loadMap(o.map);
  if (o.calibration) applyCalibration(*o.calibration, tree.get());
  if (!o.color_octree.empty()) {
    ClassTable classes = o.classes.empty() ? defaultTable(*tree) : ClassTable::load(o.classes);
    if (classes.numClasses() != tree->numClasses()) {
      throw std::runtime_error(o.classes + ": " + std::to_string(classes.numClasses()) +
                               " classes, but " + o.map + " has " +
                               std::to_string(tree->numClasses()));
    }
    const auto color = toColorOcTree(*tree, classes, colorModeFromName(o.mode));
    writeFileAtomically(o.color_octree, [&](std::ostream& out) {
      return color->write(out) && out.good();  // a killed export leaves the old file whole
    });
    std::cout << "wrote " << o.color_octree << " (ColorOcTree, " << o.mode << " colours, "
              << color->getNumLeafNodes() << " leaves)\n";
  }
  if (!o.binary.empty()) {
    saveBinaryOccupancy(*tree, o.binary);
    std::cout << "wrote " << o.binary << " (occupancy-only OcTree .bt)\n";
  }
}
}  // namespace

void addExportCommand(CLI::App& app) {
  auto o = std::make_shared<ExportOptions>();
  CLI::App* cmd = app.add_subcommand(
      "export", "Export a map to OctoMap's ColorOcTree (class, uncertainty or vacuity colours) "
                "and/or an occupancy-only .bt");
  cmd->add_option("--map", o->map, "Input map (.ot)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--color-octree", o->color_octree, "Output ColorOcTree (.ot)");
  cmd->add_option("--binary", o->binary, "Output occupancy-only OcTree (.bt)");
  cmd->add_option("--mode", o->mode,
                  "Colours: class, uncertainty (the error probability, P(label wrong): the "
                  "--calibration file's error model, else 1 - max p; grey where no class is "
                  "answered) or vacuity (u)")
      ->check(CLI::IsMember({"class", "uncertainty", "vacuity"}))
      ->capture_default_str();
  cmd->add_option("--classes", o->classes,
                  "Class table YAML for class colours (default: generated palette)")
      ->check(CLI::ExistingFile);
  addCalibrationOption(cmd, &o->calibration);
  cmd->callback([o]() { runExport(*o); });
}

}  // namespace evidential_octomap::tools
