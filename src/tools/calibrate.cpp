// `evidential_octomap calibrate`: fit the read-out cap of a dempster map (SemanticConfig::
// evidence_cap) on labelled scans of a user's own network (a validation split). The scans are
// mapped once as `map` maps them; the cap that minimises the Brier score of the map on their GT
// points (golden-section search over ln cap) is written as a parameter file that the node loads
// (rosparam: `evidence_cap`), `map` and `eval` read (--calibration FILE) and Python reads
// (evidential_octomap.read_calibration). Without it the cap follows the evidence
// (SemanticConfig::kAdaptiveCap), with constants chosen across datasets. A fit on a few scans
// can be noise (docs/results_calibrate.md), so the file keeps the adaptive cap (-1) unless the
// fitted one has the lower Brier score beyond the 95 % paired-bootstrap interval over 10 m
// blocks of these scans (--keep-fit writes the fit regardless).
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "bootstrap_report.h"
#include "commands.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evaluation/metrics.h"
#include "evidential_octomap/evaluation/paired_bootstrap.h"
#include "evidential_octomap/io.h"
#include "pipeline.h"

namespace evidential_octomap::tools {

namespace {

struct CalibrateOptions {
  std::string data, classes, out = "calibration.yaml";
  size_t scans = 0;
  SemanticConfig config;
  double resolution = 0.2;
  EvidenceOptions evidence;
  std::string evidence_name = "file";
  bool keep_fit = false;
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

std::string calibrationFile(const std::string& data, size_t scans, size_t queries,
                            const EvidenceOptions& ev, const CapFit& fit) {
  std::ostringstream file;
  file << std::setprecision(4)
       << "# evidential_octomap read-out calibration, fitted by `evidential_octomap calibrate` on\n"
       << "# " << data << " (" << scans << " scans, " << queries << " GT points, evidence "
       << describeEvidence(ev) << ").\n"
       << "# Fitted cap " << fit.cap << ": Brier score " << fit.brier << "; adaptive cap "
       << fit.adaptive << ": " << fit.adaptive_brier << "; " << differenceText(fit.difference)
       << ".\n"
       << (fit.written == fit.cap ? ""
                                  : "# The fit is not better beyond that interval on these "
                                    "scans, so the adaptive cap (-1) is kept; --keep-fit writes "
                                    "the fit.\n")
       << "# Load it as node parameters (rosparam load, or the launch files' config:=), pass it\n"
       << "# to `evidential_octomap map --calibration FILE`, or read it in Python with\n"
       << "# evidential_octomap.read_calibration(FILE).\n"
       << "evidence_cap: " << fit.written << "\n";
  return file.str();
}

void runCalibrate(const CalibrateOptions& o) {
  const ClassTable classes = ClassTable::load(o.classes);
  EvidenceOptions ev = o.evidence;
  finishEvidenceOptions(o.evidence_name, o.classes, classes, &ev);
  const Dataset dataset = Dataset::open(o.data, classes, ev.conversion);
  if (!dataset.hasLabels()) throw std::runtime_error(o.data + ": calibrate needs labels/ (GT)");
  if (o.config.rule != "dempster") throw std::runtime_error("calibrate fits the dempster cap");
  const std::vector<Scan> scans = loadScans(dataset, o.scans, !o.quiet);
  const Protocol protocol = makeProtocol("reconstruction", scans.size());
  const auto evidence = deriveEvidenceFor(scans, protocol.map_scans, ev, classes, {});
  MapRun run = runMapping(scans, protocol.map_scans, evidence, classes, o.config, o.resolution,
                          !o.quiet, "mapping");
  const std::vector<Query> queries =
      buildQueries(scans, protocol.query_scans, classes.ignore_class, nullptr, nullptr);
  const CapFit fit = fitCap(run.tree.get(), queries, classes.ignore_class, o.keep_fit);
  writeFileAtomically(o.out, calibrationFile(o.data, scans.size(), queries.size(), ev, fit));
  std::cout << std::setprecision(4) << "evidence cap " << fit.cap << ": Brier " << fit.brier
            << " (the adaptive cap " << fit.adaptive << " gives " << fit.adaptive_brier << ")\n"
            << differenceText(fit.difference) << "\nwrote evidence_cap: " << fit.written
            << (fit.written == fit.cap ? ""
                                       : " (adaptive: the fit is not better beyond the interval)")
            << " to " << o.out << "\n";
}

}  // namespace

void addCalibrateCommand(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate",
      "Fit the dempster read-out cap on labelled scans of your own network (a validation "
      "split) and write it as a parameter file for the node (and --evidence-cap for map)");
  addDataOptions(cmd, &o->data, "Dataset directory with labels/ and evidence", &o->classes);
  cmd->add_option("--out", o->out, "Parameter file to write")->capture_default_str();
  cmd->add_option("--scans", o->scans, "Use only the first N scans (0: all)")
      ->capture_default_str();
  addConfigOptions(cmd, &o->config, &o->resolution);
  addEvidenceOptions(cmd, &o->evidence, &o->evidence_name);
  cmd->add_flag("--keep-fit", o->keep_fit,
                "Write the fitted cap even when its Brier score is not lower than the adaptive "
                "cap's beyond the 95 % bootstrap interval (by default the file then keeps -1)");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress bars");
  cmd->callback([o]() { runCalibrate(*o); });
}

}  // namespace evidential_octomap::tools
