// Subcommands of the `evidential_octomap` CLI; each lives in its own file with its own --help.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "evidence_sources.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap::tools {

void addMapCommand(CLI::App& app);      // map_sequence.cpp
void addEvalCommand(CLI::App& app);     // evaluate.cpp
void addCompareCommand(CLI::App& app);  // compare.cpp
void addExportCommand(CLI::App& app);   // export_color.cpp
void addMergeCommand(CLI::App& app);    // merge.cpp
void addInfoCommand(CLI::App& app);     // info.cpp

// --- shared option groups (defaults come from the structs, never restated) -----------------
// Mapping parameters of SemanticConfig plus the tree resolution.
void addConfigOptions(CLI::App* cmd, SemanticConfig* config, double* resolution);
// --evidence, -E, --knn-k, --knn-radius; the source name is parsed into options->source by
// finishEvidenceOptions().
void addEvidenceOptions(CLI::App* cmd, EvidenceOptions* options, std::string* source_name);
void finishEvidenceOptions(const std::string& source_name, EvidenceOptions* options);

// Caption lines shared by every PNG and the reports.
std::vector<std::string> captionLines(const std::string& what, const std::string& variant,
                                      const std::string& evidence, bool derived,
                                      const std::string& protocol,
                                      const std::string& predictions_note);

// "dempster", "dempster w/o adaptive length", "sbki", ... of a config.
std::string variantName(const SemanticConfig& config);

// Creates the directory (and parents); throws naming it on failure.
void makeDirectories(const std::string& dir);

}  // namespace evidential_octomap::tools
