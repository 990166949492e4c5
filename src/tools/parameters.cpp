// `evidential_octomap parameters`: prints docs/parameters.md, the reference of every setting
// (made from the one list in settings.h; a test compares the committed file with it).
#include <iostream>

#include "commands.h"
#include "evidential_octomap/settings.h"

namespace evidential_octomap::tools {

void addParametersCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "parameters",
      "Print the parameter reference (docs/parameters.md): every setting's type, default, valid "
      "values, whether a map stores it, its ROS and CLI names and help");
  cmd->callback([] { std::cout << parameterReference(); });
}

}  // namespace evidential_octomap::tools
