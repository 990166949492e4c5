#include "report.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

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
  j["effective_downsampling"] = config.effectiveDownsampling();
  return j;
}

void fillTreeStats(const EvidentialOcTree& tree, RunReport* r) {
  r->leaves = tree.getNumLeafNodes();
  r->semantic_nodes = tree.numSemanticNodes();
  r->memory_bytes = tree.memoryUsage();
}

nlohmann::json toJson(const RunReport& r, const ClassTable& classes) {
  using nlohmann::json;
  const int C = classes.numClasses();
  json per_class = json::array();
  for (int c = 0; c < C; ++c) {
    if (c == classes.ignore_class) continue;
    per_class.push_back({{"class", c},
                         {"name", classes.names[c]},
                         {"gt_queries", r.map.confusion_all.gtCount(c)},
                         {"present_in_gt", r.map.confusion_all.presentInGt(c)},
                         {"map_iou", num(r.map.confusion.iou(c))},
                         {"input_iou", num(r.input.confusion.iou(c))}});
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
  j["predictions"] = r.predictions_note.empty() ? "as shipped with the dataset" : r.predictions_note;
  j["resolution"] = r.resolution;
  j["parameters"] = configJson(r.config);
  std::ostringstream printed;
  r.config.print(printed);
  j["parameters_text"] = printed.str();
  j["map"] = {{"queries", r.map.queries},
              {"covered", r.map.covered},
              {"o_acc", num(r.map.occupied_accuracy)},
              {"miou", num(r.map.miou)},
              {"acc", num(r.map.accuracy)},
              {"miou_all_queries", num(r.map.miou_all)},
              {"acc_all_queries", num(r.map.accuracy_all)},
              {"brier", num(r.map.brier)},
              {"uncertainty_normalisation", r.map.scale.describe()},
              {"uncertainty_scaled", r.map.scale.scaled},
              {"uncertainty_min", r.map.scale.min},
              {"uncertainty_max", r.map.scale.max},
              {"mean_u_correct", num(r.map.mean_u_correct)},
              {"mean_u_wrong", num(r.map.mean_u_wrong)}};
  j["input_predictions"] = {{"queries", r.input.queries},
                            {"miou", num(r.input.miou)},
                            {"acc", num(r.input.accuracy)}};
  j["per_class"] = per_class;
  j["timing"] = {{"what", "insertSemanticScan wall time per scan (loading and evidence "
                          "derivation excluded)"},
                 {"ms_per_scan", r.ms_per_scan},
                 {"ms_per_scan_median", median(r.ms_per_scan)},
                 {"ms_occupancy_total", r.totals.ms_occupancy},
                 {"ms_kernel_total", r.totals.ms_kernel},
                 {"ms_update_total", r.totals.ms_update}};
  j["insert"] = {{"points_in", r.totals.points_in},
                 {"points_skipped", r.totals.points_skipped},
                 {"points_beyond_range", r.totals.points_beyond_range},
                 {"semantic_points", r.totals.semantic_points},
                 {"points_dropped_uncertain", r.totals.points_dropped_uncertain},
                 {"voxels_updated", r.totals.voxels_updated}};
  j["tree"] = {{"leaves", r.leaves},
               {"semantic_nodes", r.semantic_nodes},
               {"memory_bytes", r.memory_bytes}};
  return j;
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
  s << "\n- predictions: " << (r.predictions_note.empty() ? "as shipped with the dataset"
                                                           : r.predictions_note)
    << "\n- resolution " << r.resolution << " m; BS uncertainty: " << r.map.scale.describe()
    << "\n- queries: " << r.map.queries << " GT-labelled points (class "
    << (classes.ignore_class >= 0 ? classes.names[classes.ignore_class] : std::string("none"))
    << " excluded), covered " << r.map.covered << "\n\n";
  s << "| | mIoU % | Acc % | O.Acc % | BS | ms/scan (median) |\n|---|---|---|---|---|---|\n";
  s << "| input predictions, per point | " << percent(r.input.miou) << " | "
    << percent(r.input.accuracy) << " | – | – | – |\n";
  s << "| map (" << r.variant << ") | " << percent(r.map.miou) << " | "
    << percent(r.map.accuracy) << " | " << percent(r.map.occupied_accuracy) << " | "
    << std::fixed << std::setprecision(4) << r.map.brier << " | " << std::setprecision(0)
    << median(r.ms_per_scan) << " |\n\n";
  s << "Over all queries (an uncovered query counts as wrong): mIoU " << percent(r.map.miou_all)
    << " %, Acc " << percent(r.map.accuracy_all) << " %. Mean scaled uncertainty of covered "
    << "correct / wrong queries: " << std::setprecision(3) << r.map.mean_u_correct << " / "
    << r.map.mean_u_wrong << ".\n\n";
  s << "| class | GT queries | map IoU % | input IoU % |\n|---|---|---|---|\n";
  for (int c = 0; c < classes.numClasses(); ++c) {
    if (c == classes.ignore_class || !r.map.confusion_all.presentInGt(c)) continue;
    s << "| " << classes.names[c] << " | " << r.map.confusion_all.gtCount(c) << " | "
      << percent(r.map.confusion.iou(c)) << " | " << percent(r.input.confusion.iou(c)) << " |\n";
  }
  s << "\nParameters (SemanticConfig):\n\n```\n";
  r.config.print(s);
  s << "```\n";
  return s.str();
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  out << text;
  if (!out) throw std::runtime_error(path + ": write failed");
}

}  // namespace evidential_octomap::tools
