// `evidential_octomap eval --map map.ot --data DIR`: metrics of any saved map on a dataset's
// GT-labelled points (metrics.h), beside the input predictions' per-point metrics.
#include <iostream>
#include <memory>

#include "commands.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/io.h"
#include "pipeline.h"
#include "report.h"
#include "synthetic.h"

namespace evidential_octomap::tools {

namespace {
struct EvalOptions {
  std::string map, data, classes, out, protocol = "reconstruction";
  EvidenceOptions evidence;
  std::string evidence_name = "onehot";
  std::string evidence_note = "unknown (not stored in the .ot; see the metrics.json of the run)";
  size_t scans = 0;
  bool synthetic = false;
  NoiseModel noise;
  double evidence_cap = -2.0;  // < -1: the map's own
  std::shared_ptr<const Calibration> calibration;
};

void runEval(const EvalOptions& o) {
  const std::unique_ptr<EvidentialOcTree> tree = loadMap(o.map);
  const ClassTable classes = ClassTable::load(o.classes);
  if (classes.numClasses() != tree->numClasses()) {
    throw std::runtime_error(o.classes + " has " + std::to_string(classes.numClasses()) +
                             " classes, " + o.map + " has " + std::to_string(tree->numClasses()));
  }
  if (o.evidence_cap >= SemanticConfig::kAdaptiveCap) {  // only the read-out changes: the stored evidence is the same
    SemanticConfig config = tree->config();
    config.evidence_cap = o.evidence_cap;
    tree->setConfig(config);
  }
  if (o.calibration) applyCalibration(*o.calibration, tree.get());
  EvidenceOptions ev = o.evidence;
  finishEvidenceOptions(o.evidence_name, o.classes, classes, &ev);
  const Dataset dataset = Dataset::open(o.data, classes, ev.conversion);
  ev.files = dataset.describeEvidenceFiles();
  std::vector<Scan> scans = loadScans(dataset, o.scans, true);
  std::string predictions_note;
  if (o.synthetic) {
    predictions_note = useSyntheticPredictions(&scans, classes, o.noise);
  } else if (!dataset.hasPredictions()) {
    predictions_note = "none in the dataset (input metrics count every query as unlabelled)";
  }
  const Protocol protocol = makeProtocol(o.protocol, scans.size());
  // The input row: the per-point evidence of the query scans, derived as `map` derives it.
  std::vector<std::vector<float>> evidence;
  std::vector<float> query_evidence;
  std::string input_description = "input predictions (hard labels), per point";
  if (!derivedFromHardLabels(ev.source) || dataset.hasPredictions() || o.synthetic) {
    evidence = deriveEvidenceFor(scans, protocol.map_scans, ev, classes, protocol.query_scans);
    input_description = inputDescription(ev);
  }
  const std::vector<Query> queries =
      buildQueries(scans, protocol.query_scans, classes.ignore_class,
                   evidence.empty() ? nullptr : &evidence, &query_evidence);
  RunReport r;
  r.dataset = o.data;
  r.protocol = protocol.name;
  for (size_t s : protocol.map_scans) r.map_scans.push_back(scans[s].name + "(assumed)");
  for (size_t s : protocol.query_scans) r.query_scans.push_back(scans[s].name);
  r.variant = variantName(tree->config()) + " (saved map " + o.map + ")";
  r.evidence_source = "unknown";
  r.evidence_description = o.evidence_note;
  r.evidence_derived = false;
  r.evidence_kind = "unknown";
  r.predictions_note = predictions_note;
  r.config = tree->config();
  r.resolution = tree->getResolution();
  r.map = evaluateMap(*tree, queries, classes.ignore_class);
  r.input = evaluateInput(queries, query_evidence, classes.numClasses(), classes.ignore_class);
  r.input_description = input_description;
  fillTreeStats(*tree, &r);
  const std::string md = toMarkdown(r, classes);
  std::cout << md;
  if (!o.out.empty()) {
    makeDirectories(o.out);
    writeText(o.out + "/metrics.json", toJson(r, classes).dump(2) + "\n");
    writeText(o.out + "/metrics.md", md);
    std::cout << "\nwrote " << o.out << "/{metrics.json,metrics.md}\n";
  }
}
}  // namespace

void addEvalCommand(CLI::App& app) {
  auto o = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "Metrics of a saved map on a dataset's GT-labelled points: O.Acc, per-class IoU, "
      "mIoU, Acc, Brier score, and the input predictions' per-point metrics");
  cmd->add_option("--map", o->map, "Map (.ot)")->required()->check(CLI::ExistingFile);
  addDataOptions(cmd, &o->data, "Dataset directory (or a single .bin scan)", &o->classes);
  cmd->add_option("--protocol", o->protocol,
                  "Which scans are queried: reconstruction (all) or held-out (second half)")
      ->check(CLI::IsMember({"reconstruction", "held-out"}))
      ->capture_default_str();
  cmd->add_option("--scans", o->scans, "Use only the first N scans (0: all)")
      ->capture_default_str();
  cmd->add_option("--out", o->out, "Also write metrics.json and metrics.md here");
  addEvidenceOptions(cmd, &o->evidence, &o->evidence_name);
  cmd->add_option("--evidence-note", o->evidence_note,
                  "What evidence the map was built from (printed in the outputs)");
  cmd->add_option("--evidence-cap", o->evidence_cap,
                  "dempster: read the opinions with this evidence cap instead of the map's own "
                  "(0: no cap); the stored evidence is unchanged");
  addCalibrationOption(cmd, &o->calibration);
  cmd->add_flag("--synthetic-predictions", o->synthetic,
                "Input predictions = GT with the synthetic noise model (as `map`)");
  cmd->add_option("--noise-point-rate", o->noise.point_rate, "Synthetic point-noise rate")
      ->capture_default_str();
  cmd->add_option("--noise-region-rate", o->noise.region_rate, "Synthetic region-flip rate")
      ->capture_default_str();
  cmd->add_option("--noise-seed", o->noise.seed, "Synthetic noise seed")->capture_default_str();
  cmd->callback([o]() { runEval(*o); });
}

}  // namespace evidential_octomap::tools
