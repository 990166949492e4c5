// evidential_octomap: offline mapping, evaluation, comparison and conversion of evidential
// semantic OctoMaps. One binary, one subcommand per file (see commands.h).
#include <exception>
#include <iostream>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{
      "evidential_octomap: uncertainty-aware semantic OctoMaps (Dempster-Shafer fusion of "
      "per-point evidence). Run '<command> --help' for the options of each command."};
  app.require_subcommand(1);
  namespace t = evidential_octomap::tools;
  t::addMapCommand(app);
  t::addEvalCommand(app);
  t::addCompareCommand(app);
  t::addExportCommand(app);
  t::addMergeCommand(app);
  t::addInfoCommand(app);
  t::addTilesCommand(app);
  t::addFeaturesCommand(app);
  t::addParametersCommand(app);
  t::addCalibrateCommand(app);
  t::addGenerateCommand(app);
  t::setCommandLine(argc, argv);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
