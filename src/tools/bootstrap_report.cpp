// compare's paired-bootstrap table (bootstrap_report.h).
#include "bootstrap_report.h"

#include <cmath>
#include <sstream>

#include "report.h"

namespace evidential_octomap::tools {

namespace {
nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json intervalJson(const BootstrapInterval& i) {
  return {{"estimate", num(i.estimate)},
          {"lower", num(i.lower)},
          {"upper", num(i.upper)},
          {"share_of_replicates_above_0", num(i.share_positive)}};
}

std::string signedFixed(double v, int decimals) {
  return (std::isfinite(v) && v > 0.0 ? "+" : "") + fixed(v, decimals);
}

// "+0.12 [−0.05, +0.30]" (scale 100: mIoU points)
std::string intervalCell(const BootstrapInterval& i, double scale, int decimals) {
  return signedFixed(scale * i.estimate, decimals) + " [" + signedFixed(scale * i.lower, decimals) +
         ", " + signedFixed(scale * i.upper, decimals) + "]";
}
}  // namespace

BootstrapReport::BootstrapReport(const std::vector<Query>& queries, int num_classes,
                                 int ignore_class, const BootstrapSettings& settings)
    : num_classes_(num_classes), ignore_class_(ignore_class), settings_(settings) {
  block_ = spatialBlocks(queries, settings.block_size, &blocks_);
}

BlockScores BootstrapReport::scores(const std::vector<QueryOutcome>& outcomes) const {
  return BlockScores(num_classes_, block_, blocks_, outcomes);
}

void BootstrapReport::compare(const std::string& evidence, const std::string& row_name,
                              const BlockScores& row, const BlockScores& reference,
                              const nlohmann::json& context, std::vector<std::string>* markdown,
                              nlohmann::json* json) const {
  const PairedDifference d = pairedBootstrap(row, reference, ignore_class_, settings_);
  std::ostringstream md;
  md << "| " << evidence << " | " << row_name << " | " << intervalCell(d.miou_all, 100.0, 2)
     << " | " << percent(d.miou_all.share_positive, 1) << " | " << intervalCell(d.brier, 1.0, 4)
     << " | " << percent(d.brier.share_positive, 1) << " |";
  markdown->push_back(md.str());
  nlohmann::json j = context;
  j["evidence"] = evidence;
  j["row"] = row_name;
  j["reference"] = "dempster";
  j["miou_all_difference"] = intervalJson(d.miou_all);
  j["brier_difference"] = intervalJson(d.brier);
  j["blocks"] = d.blocks;
  j["block_size_m"] = settings_.block_size;
  j["replicates"] = settings_.replicates;
  j["seed"] = settings_.seed;
  j["interval"] = 1.0 - settings_.alpha;
  json->push_back(j);
}

std::string BootstrapReport::header() {
  return "| evidence | row | Δ mIoU all (points) [95 % CI] | replicates Δ > 0 % | Δ Brier "
         "[95 % CI] | replicates Δ > 0 % |\n|---|---|---|---|---|---|\n";
}

std::string BootstrapReport::describe() const {
  std::ostringstream s;
  s << "Paired bootstrap against `dempster` (the default) of the same evidence: Δ = row − "
       "dempster on the same queries; "
    << settings_.replicates << " replicates, each drawing " << blocks_ << " spatial blocks of "
    << settings_.block_size << " m × " << settings_.block_size
    << " m (world x-y) with replacement, the same draw for both rows; seed " << settings_.seed
    << "; " << 100.0 * (1.0 - settings_.alpha)
    << " % percentile intervals (include/evidential_octomap/evaluation/paired_bootstrap.h)";
  return s.str();
}

}  // namespace evidential_octomap::tools
