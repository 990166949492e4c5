// loadMap(path): what it answers and how long it takes (docs/experiments/reliability.md).
#include <chrono>
#include <iostream>

#include "evidential_octomap/io.h"
int main(int, char** argv) {
  const auto t0 = std::chrono::steady_clock::now();
  std::string outcome;
  try {
    evidential_octomap::loadMap(argv[1]);
    outcome = "loaded";
  } catch (const std::exception& e) {
    outcome = std::string("refused: ") + e.what();
  }
  std::cout
      << argv[1] << ": " << outcome << " after "
      << std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count()
      << " ms\n";
}
