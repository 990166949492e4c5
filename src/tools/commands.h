// Subcommands of the `evidential_octomap` CLI; each lives in its own file with its own --help.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/calibration_file.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidence/evidence_sources.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap::tools {

void addMapCommand(CLI::App& app);       // map_sequence.cpp
void addEvalCommand(CLI::App& app);      // evaluate.cpp
void addCompareCommand(CLI::App& app);   // compare.cpp
void addExportCommand(CLI::App& app);    // export_color.cpp
void addMergeCommand(CLI::App& app);     // merge.cpp
void addInfoCommand(CLI::App& app);      // info.cpp
void addTilesCommand(CLI::App& app);     // tiles.cpp
void addFeaturesCommand(CLI::App& app);  // features.cpp
void addCalibrateCommand(CLI::App& app); // calibrate.cpp
void addGenerateCommand(CLI::App& app);  // generate.cpp
void addParametersCommand(CLI::App& app);  // parameters.cpp

// The command line as typed (main() records it), for the READMEs of generated data.
void setCommandLine(int argc, char** argv);
const std::string& commandLine();

// --- shared option groups (defaults come from the structs, never restated) -----------------
// --data (an existing path, described by data_help) and --classes (an existing class table YAML),
// both required.
void addDataOptions(CLI::App* cmd, std::string* data, const std::string& data_help,
                    std::string* classes);
// Mapping parameters of SemanticConfig plus the tree resolution.
void addConfigOptions(CLI::App* cmd, SemanticConfig* config, double* resolution);
// `--calibration FILE` (a file `calibrate` wrote, read when parsed): excludes --evidence-cap.
void addCalibrationOption(CLI::App* cmd, std::shared_ptr<const Calibration>* calibration);
// The calibration's cap in `config` and its class table checked against `classes` (throws
// std::runtime_error naming both); does nothing without a calibration.
void useCalibration(const std::shared_ptr<const Calibration>& calibration,
                    const ClassTable& classes, SemanticConfig* config);
// Prints once to stderr, for network evidence (file, learned) read without a calibration, that
// the map's error probability is uncalibrated and the command that fits it.
void warnIfUncalibrated(const EvidenceOptions& evidence, bool calibrated);
// --evidence, -E, --knn-k, --knn-radius, --learned-model; the source name is parsed into
// options->source, and an empty model path set to its default, by finishEvidenceOptions().
void addEvidenceOptions(CLI::App* cmd, EvidenceOptions* options, std::string* source_name);
void finishEvidenceOptions(const std::string& source_name, const std::string& classes_path,
                           const ClassTable& classes, EvidenceOptions* options);

// Caption lines shared by every PNG and the reports; `kind` is evidenceKind() of the source.
std::vector<std::string> captionLines(const std::string& what, const std::string& variant,
                                      const std::string& evidence, const std::string& kind,
                                      const std::string& protocol,
                                      const std::string& predictions_note);

// "dempster", "dempster w/o adaptive length", "sbki", ... of a config.
std::string variantName(const SemanticConfig& config);

// Creates the directory (and parents); throws naming it on failure.
void makeDirectories(const std::string& dir);

}  // namespace evidential_octomap::tools
