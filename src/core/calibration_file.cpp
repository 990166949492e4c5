#include "evidential_octomap/calibration_file.h"

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

namespace {
std::string trimmed(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}
}  // namespace

double readCalibrationCap(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read the calibration file");
  std::string line;
  double cap = NAN;
  for (int n = 1; std::getline(in, line); ++n) {
    line = trimmed(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    const size_t colon = line.find(':');
    const std::string where = path + ":" + std::to_string(n) + ": ";
    if (colon == std::string::npos) throw std::runtime_error(where + "expected `key: value`");
    const std::string key = trimmed(line.substr(0, colon)), value = trimmed(line.substr(colon + 1));
    if (key != "evidence_cap") {
      throw std::runtime_error(where + "unknown key '" + key + "' (a calibration file holds "
                               "evidence_cap, as written by `evidential_octomap calibrate`)");
    }
    size_t used = 0;
    try {
      cap = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    const bool adaptive = cap == SemanticConfig::kAdaptiveCap;
    if (used == 0 || used != value.size() || !std::isfinite(cap) || (cap < 0.0 && !adaptive)) {
      throw std::runtime_error(where + "evidence_cap must be -1 (adaptive) or a finite number "
                               ">= 0, not '" + value + "'");
    }
  }
  if (std::isnan(cap)) throw std::runtime_error(path + ": no evidence_cap in the calibration file");
  return cap;
}

}  // namespace evidential_octomap
