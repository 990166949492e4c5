#include "evidential_octomap/input_calibration.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "evidential_octomap/io.h"

namespace evidential_octomap {

std::string InputCalibration::problem() const {
  std::ostringstream s;
  if (!(scale >= kMinScale && scale <= kMaxScale)) {
    s << "calibration scale = " << scale << " must lie in [" << kMinScale << ", " << kMaxScale
      << "]";
  } else if (!(power >= kMinPower && power <= kMaxPower)) {
    s << "calibration power = " << power << " must lie in [" << kMinPower << ", " << kMaxPower
      << "]";
  }
  return s.str();
}

void InputCalibration::apply(float* evidence, size_t n, int num_classes) const {
  if (isIdentity()) return;
  const size_t count = n * static_cast<size_t>(num_classes);
  constexpr double kFloatMax = 3.0e38;  // keep the result a finite float
  for (size_t i = 0; i < count; ++i) {
    const double e = evidence[i];
    if (e > 0.0) evidence[i] = static_cast<float>(std::min(scale * std::pow(e, power), kFloatMax));
  }
}

std::string InputCalibration::describe() const {
  if (isIdentity()) return "uncalibrated";
  std::ostringstream s;
  s << std::setprecision(3) << "e' = " << scale << " e^" << power;
  if (labels == "consensus") s << " (fitted without labels, on cross-scan agreement)";
  if (labels == "gt") s << " (fitted on labelled scans)";
  return s.str();
}

InputCalibration InputCalibration::load(const std::string& path) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("calibration file " + path + ": " + why);
  };
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw fail("cannot open file");
  } catch (const YAML::Exception& e) {
    throw fail(std::string("not valid YAML: ") + e.what());
  }
  InputCalibration c;
  try {
    if (!root.IsMap() || !root["scale"] || !root["power"]) throw fail("needs 'scale' and 'power'");
    c.scale = root["scale"].as<double>();
    c.power = root["power"].as<double>();
    if (root["labels"]) c.labels = root["labels"].as<std::string>();
    if (root["fitted_on"]) c.fitted_on = root["fitted_on"].as<std::string>();
  } catch (const YAML::Exception& e) {
    throw fail(std::string("malformed value: ") + e.what());
  }
  const std::string problem = c.problem();
  if (!problem.empty()) throw fail(problem);
  return c;
}

void InputCalibration::save(const std::string& path) const {
  const std::string problem_now = problem();
  if (!problem_now.empty()) throw std::runtime_error("cannot save calibration: " + problem_now);
  std::ostringstream s;
  s << std::setprecision(17)
    << "# evidential_octomap input calibration: every evidence value e becomes scale * e^power\n"
    << "# before it reaches the map (docs/calibration.md).\n"
    << "scale: " << scale << "\npower: " << power << "\n"
    << "labels: " << (labels.empty() ? "none" : labels) << "\n";
  YAML::Emitter quoted;
  quoted << YAML::DoubleQuoted << fitted_on;
  s << "fitted_on: " << quoted.c_str() << "\n";
  writeFileAtomically(path, s.str());
}

}  // namespace evidential_octomap
