// `evidential_octomap calibrate`: fit the read-out of a dempster map on labelled scans of a
// user's own network (a validation split) and write the calibration file (calibration_file.h)
// that the node loads (config:=), `map`/`eval`/`compare --calibration FILE` and Python's
// read_calibration read. Two fits, on the scans mapped as `map` maps them:
//   the read-out cap (SemanticConfig::evidence_cap): the cap of lowest Brier score on their GT
//     points (golden-section search over ln cap). A fit on a few scans can be noise
//     (docs/experiments/results_calibrate.md), so the file keeps the adaptive cap (-1) unless the
//     fitted one is better beyond the 95 % paired-bootstrap interval over 10 m blocks (--keep-fit
//     writes it regardless);
//   the error model (error_model.h): P(label wrong) from everything the voxel holds, on the
//     queries of two maps (every scan mapped and queried; the odd scans mapped, the even ones
//     queried, so that it also sees voxels whose points were not the query's), the penalty
//     chosen on held-out folds of 10 m blocks; its out-of-fold AUROC is printed beside each
//     single output's on the same queries.
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "bootstrap_report.h"
#include "commands.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evaluation/metrics.h"
#include "evidential_octomap/evaluation/paired_bootstrap.h"
#include "evidential_octomap/calibration_file.h"
#include "evidential_octomap/error_model.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/safe_key.h"
#include "pipeline.h"

namespace evidential_octomap::tools {

namespace {

constexpr int kErrorModelFolds = 5;  // of the 10 m blocks

struct CalibrateOptions {
  std::string data, classes, out = "calibration.yaml";
  size_t scans = 0;
  SemanticConfig config;
  double resolution = 0.2;
  EvidenceOptions evidence;
  std::string evidence_name = "file";
  bool keep_fit = false;
  bool error_model = true;
  bool quiet = false;
};

// Reads the map with a fixed cap (only the read-out changes).
void setCap(EvidentialOcTree* tree, double cap) {
  SemanticConfig c = tree->config();
  c.evidence_cap = cap;
  tree->setConfig(c);
}

double brierWithCap(EvidentialOcTree* tree, const std::vector<Query>& queries, int ignore_class,
                    double cap) {
  setCap(tree, cap);
  return evaluateMap(*tree, queries, ignore_class).quality.brier;
}

// The fitted cap's Brier score minus the adaptive cap's, paired over spatial blocks (compare's
// bootstrap).
BootstrapInterval brierDifference(EvidentialOcTree* tree, const std::vector<Query>& queries,
                                  int ignore_class, double fitted, double adaptive) {
  const BootstrapSettings settings;
  const BootstrapReport report(queries, tree->numClasses(), ignore_class, settings);
  const auto scores = [&](double cap) {
    setCap(tree, cap);
    std::vector<QueryOutcome> outcomes;
    evaluateMap(*tree, queries, ignore_class, &outcomes);
    return report.scores(outcomes);
  };
  return pairedBootstrap(scores(fitted), scores(adaptive), ignore_class, settings).brier;
}

// The cap of lowest Brier score, the adaptive cap against it and what the file keeps.
struct CapFit {
  double cap = 0.0, brier = 0.0;
  double adaptive = 0.0, adaptive_brier = 0.0;
  BootstrapInterval difference;  // fit minus adaptive
  double written = 0.0;          // the fit, or SemanticConfig::kAdaptiveCap
};

CapFit fitCap(EvidentialOcTree* tree, const std::vector<Query>& queries, int ignore_class,
              bool keep_fit) {
  const auto brier = [&](double log_cap) {
    return brierWithCap(tree, queries, ignore_class, std::exp(log_cap));
  };
  // Golden-section search on ln cap in [ln 0.5, ln 100] (the Brier score is unimodal in it).
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = std::log(0.5), b = std::log(100.0), x1 = b - r * (b - a), x2 = a + r * (b - a);
  double f1 = brier(x1), f2 = brier(x2);
  for (int i = 0; i < 14; ++i) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - r * (b - a), f1 = brier(x1);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + r * (b - a), f2 = brier(x2);
    }
  }
  CapFit fit;
  fit.cap = std::exp((a + b) / 2.0);
  fit.brier = brier(std::log(fit.cap));
  // The cap -1 stands for in the file, whatever cap the given settings read with.
  fit.adaptive = SemanticConfig::adaptiveEvidenceCap(tree->meanPointLogEvidence());
  fit.adaptive_brier = brier(std::log(fit.adaptive));
  fit.difference = brierDifference(tree, queries, ignore_class, fit.cap, fit.adaptive);
  const bool better = fit.difference.upper < 0.0;
  fit.written = better || keep_fit ? fit.cap : SemanticConfig::kAdaptiveCap;
  return fit;
}

std::string differenceText(const BootstrapInterval& d) {
  std::ostringstream text;
  text << std::setprecision(3) << "Brier difference " << d.estimate << " [" << d.lower << ", "
       << d.upper << "] (95 %, paired bootstrap over 10 m blocks)";
  return text.str();
}

// The 10 m block of a point, the same number in every map and query set (the fit's folds are
// blocks, so that a place is never in the rows a model is fitted on and judged on).
uint32_t blockOf(const octomap::point3d& p) {
  const double side = BootstrapSettings().block_size;
  const auto x = uint32_t(int32_t(std::floor(p.x() / side)));
  const auto y = uint32_t(int32_t(std::floor(p.y() / side)));
  return (x * 73856093u) ^ (y * 19349663u);
}

// The error model's rows: each labelled query's voxel features, whether its label is wrong and
// its block.
void addErrorRows(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                  int ignore_class, std::vector<ErrorRow>* rows) {
  const int C = tree.numClasses();
  float payload[EvidentialOcTree::kMaxClasses];
  for (const Query& q : queries) {
    octomap::OcTreeKey key;
    if (q.gt < 0 || q.gt >= C || q.gt == ignore_class) continue;
    if (!safeCoordToKey(tree, q.point_W, &key) || !tree.answerPayload(key, payload)) continue;
    const VoxelOpinion o = tree.rule().readout(payload, C);
    if (o.label < 0) continue;
    rows->push_back({ErrorModel::features(payload, o, C), o.label, o.label != q.gt,
                     blockOf(q.point_W)});
  }
}

// Out-of-fold AUROC of the model and of each single output on the same rows.
struct ErrorModelReport {
  size_t rows = 0, wrong = 0;
  double model_auroc = 0.0;
  std::vector<std::pair<std::string, double>> single;  // output, AUROC
  std::string text() const {
    std::ostringstream t;
    t << std::setprecision(3) << "error model, AUROC of wrong labels on held-out 10 m blocks ("
      << rows << " voxel queries, " << wrong << " wrong): model " << model_auroc;
    for (const auto& [name, value] : single) t << ", " << name << " " << value;
    return t.str();
  }
};

// AUROC within each held-out fold, averaged with the fold's rows as weights: each fold is scored
// with the one model fitted without it, as a map is read with one model (pooled over folds, the
// folds' models would be ranked against each other).
double foldAuroc(const std::vector<ErrorRow>& rows, const std::function<double(size_t)>& score) {
  double sum = 0.0, weight = 0.0;
  for (int k = 0; k < kErrorModelFolds; ++k) {
    std::vector<float> s;
    std::vector<uint8_t> wrong;
    for (size_t i = 0; i < rows.size(); ++i) {
      if (int(rows[i].fold % kErrorModelFolds) != k) continue;
      s.push_back(float(score(i)));
      wrong.push_back(rows[i].wrong);
    }
    const double a = auroc(s, wrong);
    if (!std::isfinite(a)) continue;  // a fold without wrong (or right) labels
    sum += a * double(s.size());
    weight += double(s.size());
  }
  return weight > 0.0 ? sum / weight : NAN;
}

ErrorModelReport reportOf(const std::vector<ErrorRow>& rows, const std::vector<double>& oof) {
  ErrorModelReport r;
  r.rows = rows.size();
  for (const ErrorRow& row : rows) r.wrong += row.wrong;
  r.model_auroc = foldAuroc(rows, [&](size_t i) { return oof[i]; });
  // Each feature in the direction in which it flags errors (label_share: low is worse).
  for (int f = 0; f < ErrorModel::kNumFeatures; ++f) {
    const std::string name = ErrorModel::featureNames()[f];
    if (name == "evidence_mass") continue;  // a size, not an uncertainty
    const double sign = name == "label_share" ? -1.0 : 1.0;
    r.single.emplace_back(name, foldAuroc(rows, [&](size_t i) { return sign * rows[i].x[f]; }));
  }
  return r;
}

struct ErrorModelFitRun {
  std::shared_ptr<const ErrorModel> model;
  ErrorModelReport report;
};

ErrorModelFitRun fitErrorModelOn(const std::vector<Scan>& scans,
                                 const std::vector<std::vector<float>>& evidence,
                                 const ClassTable& classes, const SemanticConfig& config,
                                 double resolution, const EvidentialOcTree& all_scans_map,
                                 const std::vector<Query>& all_queries, bool progress) {
  std::vector<ErrorRow> rows;
  addErrorRows(all_scans_map, all_queries, classes.ignore_class, &rows);
  std::vector<size_t> odd, even;
  for (size_t s = 0; s < scans.size(); ++s) (s % 2 ? odd : even).push_back(s);
  if (!odd.empty() && !even.empty()) {
    const MapRun half = runMapping(scans, odd, evidence, classes, config, resolution, progress,
                                   "mapping the odd scans");
    addErrorRows(*half.tree, buildQueries(scans, even, classes.ignore_class, nullptr, nullptr),
                 classes.ignore_class, &rows);
  }
  const ErrorModelFitResult fit = fitErrorModel(rows, classes.numClasses(), kErrorModelFolds);
  return {std::make_shared<const ErrorModel>(fit.model), reportOf(rows, fit.out_of_fold)};
}

std::string fileComment(const std::string& data, size_t scans, size_t queries,
                        const EvidenceOptions& ev, const CapFit& fit,
                        const ErrorModelFitRun& error) {
  std::ostringstream text;
  text << std::setprecision(4)
       << "evidential_octomap calibration, fitted by `evidential_octomap calibrate` on\n"
       << data << " (" << scans << " scans, " << queries << " GT points, evidence "
       << describeEvidence(ev) << ").\n"
       << "Fitted cap " << fit.cap << ": Brier score " << fit.brier << "; adaptive cap "
       << fit.adaptive << ": " << fit.adaptive_brier << "; " << differenceText(fit.difference)
       << ".\n"
       << (fit.written == fit.cap ? ""
                                  : "The fit is not better beyond that interval on these scans, "
                                    "so the adaptive cap (-1) is kept; --keep-fit writes the fit.\n")
       << (error.model ? error.report.text() + ".\n" : "")
       << "Load it as node parameters (rosparam load, or the launch files' config:=), pass it\n"
       << "to `evidential_octomap map --calibration FILE`, or read it in Python with\n"
       << "evidential_octomap.read_calibration(FILE).";
  return text.str();
}

void runCalibrate(const CalibrateOptions& o) {
  const ClassTable classes = ClassTable::load(o.classes);
  EvidenceOptions ev = o.evidence;
  finishEvidenceOptions(o.evidence_name, o.classes, classes, &ev);
  const Dataset dataset = Dataset::open(o.data, classes, ev.conversion);
  if (!dataset.hasLabels()) throw std::runtime_error(o.data + ": calibrate needs labels/ (GT)");
  if (o.config.rule != "dempster") throw std::runtime_error("calibrate fits the dempster rule");
  const std::vector<Scan> scans = loadScans(dataset, o.scans, !o.quiet);
  const Protocol protocol = makeProtocol("reconstruction", scans.size());
  const auto evidence = deriveEvidenceFor(scans, protocol.map_scans, ev, classes, {});
  MapRun run = runMapping(scans, protocol.map_scans, evidence, classes, o.config, o.resolution,
                          !o.quiet, "mapping");
  const std::vector<Query> queries =
      buildQueries(scans, protocol.query_scans, classes.ignore_class, nullptr, nullptr);
  const CapFit fit = fitCap(run.tree.get(), queries, classes.ignore_class, o.keep_fit);
  SemanticConfig config = o.config;
  config.evidence_cap = fit.written;
  setCap(run.tree.get(), fit.written);
  ErrorModelFitRun error;
  if (o.error_model) {
    error = fitErrorModelOn(scans, evidence, classes, config, o.resolution, *run.tree, queries,
                            !o.quiet);
  }
  Calibration calibration;
  calibration.rule = config.rule;
  calibration.classes = classes.names;
  calibration.evidence_cap = fit.written;
  calibration.error_model = error.model;
  writeFileAtomically(o.out, calibrationText(calibration, fileComment(o.data, scans.size(),
                                                                        queries.size(), ev, fit,
                                                                        error)));
  std::cout << std::setprecision(4) << "evidence cap " << fit.cap << ": Brier " << fit.brier
            << " (the adaptive cap " << fit.adaptive << " gives " << fit.adaptive_brier << ")\n"
            << differenceText(fit.difference) << "\nwrote evidence_cap: " << fit.written
            << (fit.written == fit.cap ? ""
                                       : " (adaptive: the fit is not better beyond the interval)")
            << "\n"
            << (error.model ? error.report.text() + "\n" : "") << "wrote " << o.out << "\n";
}

}  // namespace

void addCalibrateCommand(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate",
      "Fit the dempster read-out cap and the map's error probability on labelled scans of your "
      "own network (a validation split) and write the calibration file that the node, map, "
      "eval, compare and Python read");
  addDataOptions(cmd, &o->data, "Dataset directory with labels/ and evidence", &o->classes);
  cmd->add_option("--out", o->out, "Parameter file to write")->capture_default_str();
  cmd->add_option("--scans", o->scans, "Use only the first N scans (0: all)")
      ->capture_default_str();
  addConfigOptions(cmd, &o->config, &o->resolution);
  addEvidenceOptions(cmd, &o->evidence, &o->evidence_name);
  cmd->add_flag("--keep-fit", o->keep_fit,
                "Write the fitted cap even when its Brier score is not lower than the adaptive "
                "cap's beyond the 95 % bootstrap interval (by default the file then keeps -1)");
  cmd->add_flag("!--no-error-model", o->error_model,
                "Fit the read-out cap only (the map's error probability stays 1 - max p)");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress bars");
  cmd->callback([o]() { runCalibrate(*o); });
}

}  // namespace evidential_octomap::tools
