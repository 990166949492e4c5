// Metrics reports of one mapping run: JSON (every parameter, the evidence source, the protocol)
// and markdown. Captions and the markdown say when evidence is derived from hard labels and when
// predictions are synthetic.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evaluation/metrics.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap::tools {

struct RunReport {
  std::string dataset;                    // path given on the command line
  std::string protocol;                   // reconstruction | held-out
  std::vector<std::string> map_scans;     // scan names mapped
  std::vector<std::string> query_scans;   // scan names queried
  std::string variant;                    // e.g. "dempster", "dempster w/o adaptive length"
  std::string evidence_source;            // file | onehot | knn-vote | confusion | unknown
  std::string evidence_description;       // describeEvidence()
  bool evidence_derived = true;           // derived from hard labels
  std::string evidence_kind = "derived";  // evidenceKind(): derived | learned (cross-fitted) | ..
  std::string predictions_note;           // e.g. synthetic noise model; empty for real ones
  SemanticConfig config;
  double resolution = 0.2;
  MapMetrics map;
  QualityMetrics input;                      // the input's per-point answers on the same queries
  std::string input_description;             // e.g. "input evidence (onehot, E=20), per point"
  long long occupied_without_endpoint = -1;  // -1: not measured (e.g. eval of a saved map)
  std::vector<double> ms_per_scan;
  InsertStats totals;
  size_t leaves = 0, semantic_nodes = 0, memory_bytes = 0;
  double mean_point_log_evidence = 0.0;  // m, which the adaptive cap follows
  double evidence_cap = 0.0;  // dempster's read-out cap in use (0: none; NaN: other rule)
};

// Every SemanticConfig field, parsed from SemanticConfig::print (so new fields appear too).
nlohmann::json configJson(const SemanticConfig& config);
// The metric set of one row (map or input) as JSON.
nlohmann::json qualityJson(const QualityMetrics& q);
nlohmann::json toJson(const RunReport& report, const ClassTable& classes);
std::string toMarkdown(const RunReport& report, const ClassTable& classes);
// Fills leaves / semantic_nodes / memory_bytes and the read-out cap with its m from the tree.
void fillTreeStats(const EvidentialOcTree& tree, RunReport* report);

// Writes text to a file; throws std::runtime_error naming the path.
void writeText(const std::string& path, const std::string& text);

double median(std::vector<double> values);
std::string percent(double fraction, int decimals = 1);  // "38.0", "nan" -> "–"
std::string fixed(double value, int decimals);           // "0.1234", "nan" -> "–"

// The metric columns shared by `map`, `eval` and `compare` tables: accuracy and calibration,
// then error detection (AUROC and AURC of every uncertainty output). Headers end with the rule
// line; cells start and end with "|". NaN (e.g. coverage of the input row) prints as "–".
std::string qualityHeader(const std::string& leading_columns);
std::string qualityCells(const QualityMetrics& q, double semantic_coverage,
                         double occupancy_coverage);
std::string detectionHeader(const std::string& leading_columns);
std::string detectionCells(const QualityMetrics& q);

}  // namespace evidential_octomap::tools
