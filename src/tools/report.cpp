#include "report.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "evidential_octomap/io.h"

namespace evidential_octomap::tools {

namespace {
nlohmann::json scalarFromText(const std::string& v) {
  if (v == "true") return true;
  if (v == "false") return false;
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (end != v.c_str() && *end == '\0') return d;
  return v;
}

nlohmann::json num(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}
}  // namespace

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string percent(double fraction, int decimals) {
  if (!std::isfinite(fraction)) return "–";
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << 100.0 * fraction;
  return s.str();
}

nlohmann::json configJson(const SemanticConfig& config) {
  std::ostringstream printed;
  config.print(printed);
  nlohmann::json j = nlohmann::json::object();
  std::istringstream in(printed.str());
  std::string line;
  while (std::getline(in, line)) {
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string key = line.substr(0, colon), value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(' '));
    // "3 (0 used)" -> keep the value; what is used is its own entry (effective_*).
    const size_t paren = value.find(" (");
    if (paren != std::string::npos) value = value.substr(0, paren);
    j[key] = scalarFromText(value);
  }
  j["effective_gamma"] = config.effectiveGamma();
  j["effective_threshold"] = config.effectiveThreshold();
  j["effective_downsampling"] = config.effectiveDownsampling();
  return j;
}

void fillTreeStats(const EvidentialOcTree& tree, RunReport* r) {
  r->leaves = tree.getNumLeafNodes();
  r->semantic_nodes = tree.numSemanticNodes();
  r->memory_bytes = tree.memoryUsage();
  r->mean_point_log_evidence = tree.meanPointLogEvidence();
  // Only dempster reads its evidence with a cap.
  r->evidence_cap =
      tree.rule().type() == FusionRuleType::kDempster ? tree.effectiveEvidenceCap() : NAN;
}

std::string fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "–";
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << value;
  return s.str();
}

nlohmann::json qualityJson(const QualityMetrics& q) {
  using nlohmann::json;
  json detection = json::object();
  for (const ErrorDetection& d : q.error_detection) {
    json rates = json::array(), means = json::array();
    for (double v : d.error_rate_by_decile) rates.push_back(num(v));
    for (double v : d.mean_output_by_decile) means.push_back(num(v));
    detection[d.output] = {{"auroc", num(d.auroc)},
                           {"aurc", num(d.aurc)},
                           {"error_rate_by_decile", rates},
                           {"mean_output_by_decile", means}};
  }
  json reliability = json::array();
  for (const ReliabilityBin& b : q.reliability) {
    reliability.push_back({{"lower", b.lower},
                           {"upper", b.upper},
                           {"count", b.count},
                           {"mean_confidence", num(b.count ? b.mean_confidence : NAN)},
                           {"accuracy", num(b.count ? b.accuracy : NAN)}});
  }
  return {{"queries", q.queries},
          {"labelled", q.labelled},
          {"miou_all_queries", num(q.miou_all)},
          {"acc_all_queries", num(q.acc_all)},
          {"miou_labelled", num(q.miou_labelled)},
          {"acc_labelled", num(q.acc_labelled)},
          {"brier", num(q.brier)},
          {"nll", num(q.nll)},
          {"ece", num(q.ece)},
          {"error_rate_labelled", num(q.error_rate_labelled)},
          {"error_detection", detection},
          {"reliability", reliability}};
}

namespace {
// Rows: GT classes 0..C-1; columns: the predicted classes 0..C-1, then "no label".
nlohmann::json confusionJson(const ConfusionMatrix& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int gt = 0; gt < m.numClasses(); ++gt) {
    std::vector<uint64_t> row;
    for (int p = 0; p < m.numClasses(); ++p) row.push_back(m.at(gt, p));
    row.push_back(m.at(gt, -1));
    rows.push_back(row);
  }
  return rows;
}
}  // namespace

nlohmann::json toJson(const RunReport& r, const ClassTable& classes) {
  using nlohmann::json;
  const int C = classes.numClasses();
  const QualityMetrics& mq = r.map.quality;
  json per_class = json::array();
  for (int c = 0; c < C; ++c) {
    if (c == classes.ignore_class) continue;
    per_class.push_back({{"class", c},
                         {"name", classes.names[c]},
                         {"gt_queries", mq.all.gtCount(c)},
                         {"present_in_gt", mq.all.presentInGt(c)},
                         {"map_iou_all_queries", num(mq.all.iou(c))},
                         {"map_iou_labelled", num(mq.labelled_only.iou(c))},
                         {"input_iou", num(r.input.all.iou(c))}});
  }
  json j;
  j["dataset"] = r.dataset;
  j["class_table"] = classes.dataset;
  j["protocol"] = r.protocol;
  j["map_scans"] = r.map_scans;
  j["query_scans"] = r.query_scans;
  j["variant"] = r.variant;
  j["evidence_source"] = r.evidence_source;
  j["evidence_description"] = r.evidence_description;
  j["evidence_derived_from_hard_labels"] = r.evidence_derived;
  j["evidence_kind"] = r.evidence_kind;
  j["predictions"] =
      r.predictions_note.empty() ? "as shipped with the dataset" : r.predictions_note;
  j["resolution"] = r.resolution;
  j["parameters"] = configJson(r.config);
  std::ostringstream printed;
  r.config.print(printed);
  j["parameters_text"] = printed.str();
  j["metric_definitions"] = "include/evidential_octomap/evaluation/metrics.h";
  j["map"] = qualityJson(mq);
  j["confusion"] = {{"rows", "GT class"},
                    {"columns", "predicted class, then no label"},
                    {"map", confusionJson(mq.all)},
                    {"input", confusionJson(r.input.all)}};
  j["map"]["occupied"] = r.map.occupied;
  j["map"]["semantic_coverage"] = num(r.map.semantic_coverage);
  j["map"]["occupancy_coverage"] = num(r.map.occupancy_coverage);
  j["map"]["occupied_without_endpoint"] =
      r.occupied_without_endpoint >= 0 ? json(r.occupied_without_endpoint) : json(nullptr);
  j["input"] = qualityJson(r.input);
  j["input"]["description"] = r.input_description;
  j["per_class"] = per_class;
  j["timing"] = {
      {"what",
       "insertSemanticScan wall time per scan (loading and evidence "
       "derivation excluded)"},
      {"ms_per_scan", r.ms_per_scan},
      {"ms_per_scan_median", median(r.ms_per_scan)},
      {"ms_occupancy_total", r.totals.ms_occupancy},
      {"ms_kernel_total", r.totals.ms_kernel},
      {"ms_update_total", r.totals.ms_update},
      {"cpu_ms_total", r.totals.cpu_ms_occupancy + r.totals.cpu_ms_kernel + r.totals.cpu_ms_update},
      {"cpu_ms_occupancy_total", r.totals.cpu_ms_occupancy},
      {"cpu_ms_kernel_total", r.totals.cpu_ms_kernel},
      {"cpu_ms_update_total", r.totals.cpu_ms_update}};
  j["insert"] = {{"points_in", r.totals.points_in},
                 {"points_skipped", r.totals.points_skipped},
                 {"points_beyond_range", r.totals.points_beyond_range},
                 {"semantic_points", r.totals.semantic_points},
                 {"points_dropped_uncertain", r.totals.points_dropped_uncertain},
                 {"voxels_updated", r.totals.voxels_updated}};
  j["tree"] = {{"leaves", r.leaves},
               {"semantic_nodes", r.semantic_nodes},
               {"memory_bytes", r.memory_bytes},
               {"mean_point_log_evidence", r.mean_point_log_evidence},
               {"evidence_cap", num(r.evidence_cap)}};
  return j;
}

std::string qualityHeader(const std::string& lead) {
  const std::string cols =
      " mIoU all % | Acc all % | mIoU lab. % | Acc lab. % | sem. cov. % | occ. cov. % | Brier | "
      "NLL | ECE |";
  std::string rule = "|";
  for (char ch : lead + cols)
    if (ch == '|') rule += "---|";
  return "|" + lead + cols + "\n" + rule + "\n";
}

std::string qualityCells(const QualityMetrics& q, double sem, double occ) {
  std::ostringstream s;
  s << " " << percent(q.miou_all) << " | " << percent(q.acc_all) << " | "
    << percent(q.miou_labelled) << " | " << percent(q.acc_labelled) << " | " << percent(sem)
    << " | " << percent(occ) << " | " << fixed(q.brier, 4) << " | " << fixed(q.nll, 3) << " | "
    << fixed(q.ece, 4) << " |";
  return s.str();
}

std::string detectionHeader(const std::string& lead) {
  std::string cols;
  for (const std::string& o : kUncertaintyOutputs) cols += " AUROC " + o + " |";
  for (const std::string& o : kUncertaintyOutputs) cols += " AURC " + o + " |";
  cols += " error rate (labelled) % |";
  std::string rule = "|";
  for (char ch : lead + cols)
    if (ch == '|') rule += "---|";
  return "|" + lead + cols + "\n" + rule + "\n";
}

std::string detectionCells(const QualityMetrics& q) {
  std::ostringstream s;
  for (const std::string& o : kUncertaintyOutputs) {
    const ErrorDetection* d = q.detection(o);
    s << " " << fixed(d ? d->auroc : NAN, 3) << " |";
  }
  for (const std::string& o : kUncertaintyOutputs) {
    const ErrorDetection* d = q.detection(o);
    s << " " << fixed(d ? d->aurc : NAN, 4) << " |";
  }
  s << " " << percent(q.error_rate_labelled) << " |";
  return s.str();
}

std::string toMarkdown(const RunReport& r, const ClassTable& classes) {
  std::ostringstream s;
  s << "# Map metrics: " << r.variant << "\n\n";
  s << "- dataset: `" << r.dataset << "` (class table " << classes.dataset << ")\n";
  s << "- protocol: **" << r.protocol << "** — mapped scans";
  for (const auto& n : r.map_scans) s << ' ' << n;
  s << "; queried scans";
  for (const auto& n : r.query_scans) s << ' ' << n;
  s << "\n- evidence: **" << r.evidence_description << "**";
  if (r.evidence_derived) s << " — derived from hard labels, not network evidence";
  if (r.evidence_kind == "learned (cross-fitted)") {
    s << " — learned (cross-fitted): no scan's evidence comes from a model that saw its labels";
  }
  s << "\n- predictions: "
    << (r.predictions_note.empty() ? "as shipped with the dataset" : r.predictions_note)
    << "\n- resolution " << r.resolution << " m; queries: " << r.map.quality.queries
    << " GT-labelled points (class "
    << (classes.ignore_class >= 0 ? classes.names[classes.ignore_class] : std::string("none"))
    << " excluded), the same for every row\n";
  if (r.occupied_without_endpoint >= 0) {
    s << "- occupied voxels holding no ray end point: " << r.occupied_without_endpoint << "\n";
  }
  s << "\n" << qualityHeader(" |");
  s << "| " << r.input_description << " |" << qualityCells(r.input, std::nan(""), std::nan(""))
    << "\n";
  s << "| map (" << r.variant << ") |"
    << qualityCells(r.map.quality, r.map.semantic_coverage, r.map.occupancy_coverage) << "\n\n";
  s << "Error detection among labelled queries (AUROC of each uncertainty output for \"the label "
       "is wrong\"; AURC, lower is better):\n\n"
    << detectionHeader(" |");
  s << "| " << r.input_description << " |" << detectionCells(r.input) << "\n";
  s << "| map (" << r.variant << ") |" << detectionCells(r.map.quality) << "\n\n";
  const double cpu = r.totals.cpu_ms_occupancy + r.totals.cpu_ms_kernel + r.totals.cpu_ms_update;
  s << "Insert: median " << fixed(median(r.ms_per_scan), 0) << " ms/scan (wall), "
    << fixed(r.ms_per_scan.empty() ? 0.0 : cpu / double(r.ms_per_scan.size()), 0)
    << " ms/scan process CPU (mean).\n\n";
  s << "| class | GT queries | map IoU (all queries) % | map IoU (labelled) % | input IoU % |\n"
    << "|---|---|---|---|---|\n";
  for (int c = 0; c < classes.numClasses(); ++c) {
    if (c == classes.ignore_class || !r.map.quality.all.presentInGt(c)) continue;
    s << "| " << classes.names[c] << " | " << r.map.quality.all.gtCount(c) << " | "
      << percent(r.map.quality.all.iou(c)) << " | " << percent(r.map.quality.labelled_only.iou(c))
      << " | " << percent(r.input.all.iou(c)) << " |\n";
  }
  s << "\nParameters (SemanticConfig):\n\n```\n";
  r.config.print(s);
  s << "```\n";
  return s.str();
}

void writeText(const std::string& path, const std::string& text) {
  writeFileAtomically(path, text);
}

}  // namespace evidential_octomap::tools
