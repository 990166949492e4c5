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

#include "commands.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/evaluation/metrics.h"
#include "evidential_octomap/evaluation/paired_bootstrap.h"
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

// Brier score of the map read with a fixed cap (only the read-out changes).
double brierWithCap(EvidentialOcTree* tree, const std::vector<Query>& queries, int ignore_class,
                    double cap) {
  SemanticConfig c = tree->config();
  c.evidence_cap = cap;
  tree->setConfig(c);
  return evaluateMap(*tree, queries, ignore_class).quality.brier;
}

// The fitted cap's Brier score minus the adaptive cap's, paired over spatial blocks.
BootstrapInterval brierDifference(EvidentialOcTree* tree, const std::vector<Query>& queries,
                                  int ignore_class, double fitted, double adaptive) {
  const BootstrapSettings settings;
  size_t blocks = 0;
  const std::vector<uint32_t> block_of = spatialBlocks(queries, settings.block_size, &blocks);
  const auto scores = [&](double cap) {
    brierWithCap(tree, queries, ignore_class, cap);  // sets the cap
    std::vector<QueryOutcome> outcomes;
    evaluateMap(*tree, queries, ignore_class, &outcomes);
    return BlockScores(tree->numClasses(), block_of, blocks, outcomes);
  };
  return pairedBootstrap(scores(fitted), scores(adaptive), ignore_class, settings).brier;
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
  // The cap -1 stands for in the file, whatever cap the given settings read with.
  const double adaptive = SemanticConfig::adaptiveEvidenceCap(run.tree->meanPointLogEvidence());
  const auto brier = [&](double log_cap) {
    return brierWithCap(run.tree.get(), queries, classes.ignore_class, std::exp(log_cap));
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
  const double cap = std::exp((a + b) / 2.0);
  const double best = brier(std::log(cap)), with_adaptive = brier(std::log(adaptive));
  const BootstrapInterval d =
      brierDifference(run.tree.get(), queries, classes.ignore_class, cap, adaptive);
  const bool better = d.upper < 0.0;
  const double written = better || o.keep_fit ? cap : SemanticConfig::kAdaptiveCap;
  std::ostringstream difference;
  difference << std::setprecision(3) << "Brier difference " << d.estimate << " [" << d.lower
             << ", " << d.upper << "] (95 %, paired bootstrap over 10 m blocks)";
  std::ostringstream file;
  file << std::setprecision(4)
       << "# evidential_octomap read-out calibration, fitted by `evidential_octomap calibrate` on\n"
       << "# " << o.data << " (" << scans.size() << " scans, " << queries.size()
       << " GT points, evidence " << describeEvidence(ev) << ").\n"
       << "# Fitted cap " << cap << ": Brier score " << best << "; adaptive cap " << adaptive
       << ": " << with_adaptive << "; " << difference.str() << ".\n"
       << (better || o.keep_fit ? ""
                                : "# The fit is not better beyond that interval on these scans, "
                                  "so the adaptive cap (-1) is kept; --keep-fit writes the fit.\n")
       << "# Load it as node parameters (rosparam load, or the launch files' config:=), pass it\n"
       << "# to `evidential_octomap map --calibration FILE`, or read it in Python with\n"
       << "# evidential_octomap.read_calibration(FILE).\n"
       << "evidence_cap: " << written << "\n";
  writeFileAtomically(o.out, file.str());
  std::cout << std::setprecision(4) << "evidence cap " << cap << ": Brier " << best
            << " (the adaptive cap " << adaptive << " gives " << with_adaptive << ")\n"
            << difference.str() << "\nwrote evidence_cap: " << written
            << (written == cap ? "" : " (adaptive: the fit is not better beyond the interval)")
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
