// The calibration file `evidential_octomap calibrate` writes: YAML `key: value` lines (flow
// lists in brackets) and # comments, loaded by the ROS node as private parameters (rosparam,
// the launch files' config:=), by `map`/`eval`/`compare --calibration FILE` and by Python's
// read_calibration. Version 2:
//   calibration_version: 2
//   calibration_rule: dempster              the rule it was fitted for
//   calibration_classes: [name, ...]        the class table it was fitted for, in order
//   evidence_cap: -1                        the read-out cap (-1: adaptive)
//   error_model_terms: [intercept, ...]     the error model (error_model.h), when fitted
//   error_model_weights: [w, ...]
// A file without calibration_version is version 1: an evidence_cap alone.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/error_model.h"

namespace evidential_octomap {

class EvidentialOcTree;

struct Calibration {
  static constexpr int kVersion = 2;
  int version = kVersion;
  std::string rule = "dempster";
  std::vector<std::string> classes;  // empty: not recorded (version 1)
  double evidence_cap = -1.0;        // SemanticConfig::kAdaptiveCap
  std::shared_ptr<const ErrorModel> error_model;  // null: none fitted
  std::string source;                             // the file, for messages

  // "" or why it cannot read a map of these classes and rule (naming the file, both class
  // tables and both rules).
  std::string problemWith(const std::vector<std::string>& class_names,
                          const std::string& rule_name) const;
};

// The values of a calibration as they come from a file or from ROS parameters, checked: throws
// std::runtime_error naming `source` for a version this build does not know, a cap that is
// neither -1 nor finite >= 0, or an error model that does not parse.
Calibration makeCalibration(int version, const std::string& rule,
                            const std::vector<std::string>& classes, double evidence_cap,
                            const std::vector<std::string>& terms,
                            const std::vector<double>& weights, const std::string& source);

// Reads a file; throws std::runtime_error naming the file and the line when it cannot be read,
// holds an unknown key or a value that does not parse, or lacks evidence_cap.
Calibration readCalibration(const std::string& path);

// The file's text: `comment` (lines without '#', prefixed here) and the keys above.
std::string calibrationText(const Calibration& calibration, const std::string& comment);

// What a map of network evidence read without a calibration file says once (CLI, node).
inline constexpr const char* kUncalibratedNote =
    "the map's error probability is uncalibrated (1 - max p of the read-out): fit it on "
    "labelled scans of this network with `evidential_octomap calibrate --data VALIDATION_DIR "
    "--classes CLASSES.yaml --evidence file --out calibration.yaml` and read the file "
    "(docs/calibration.md)";

// Sets the tree's read-out cap and error model after checking problemWith (throws
// std::runtime_error with its message).
void applyCalibration(const Calibration& calibration, EvidentialOcTree* tree);

}  // namespace evidential_octomap
