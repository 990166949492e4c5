// compare's paired-bootstrap table: every row of a dataset/protocol/evidence block (inputs,
// reference rows, rules) against the default `dempster` of the same block, on the same queries
// and the same spatial-block draws (paired_bootstrap.h).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "evidential_octomap/evaluation/paired_bootstrap.h"

namespace evidential_octomap::tools {

class BootstrapReport {
 public:
  BootstrapReport(const std::vector<Query>& queries, int num_classes, int ignore_class,
                  const BootstrapSettings& settings);
  // One row's block statistics from its per-query outcomes (same order as the queries).
  BlockScores scores(const std::vector<QueryOutcome>& outcomes) const;
  // Appends a markdown row and a JSON entry (with `context` fields) for `row` - `reference`.
  void compare(const std::string& evidence, const std::string& row_name, const BlockScores& row,
               const BlockScores& reference, const nlohmann::json& context,
               std::vector<std::string>* markdown, nlohmann::json* json) const;
  static std::string header();
  std::string describe() const;  // the settings and block count, for the section's notes

 private:
  int num_classes_, ignore_class_;
  BootstrapSettings settings_;
  std::vector<uint32_t> block_;
  size_t blocks_ = 0;
};

}  // namespace evidential_octomap::tools
