// `evidential_octomap map`: map a SemanticKITTI-layout sequence (or one pose-less scan), then
// write map.ot, metrics.json, metrics.md and the top-down renders.
#include <iostream>
#include <memory>

#include "commands.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/io.h"
#include "pipeline.h"
#include "quality_plot.h"
#include "render.h"
#include "report.h"
#include "synthetic.h"

namespace evidential_octomap::tools {

namespace {

struct MapOptions {
  std::string data, classes, out = "out/map";
  std::string protocol = "reconstruction";
  size_t scans = 0;
  SemanticConfig config;
  double resolution = 0.2;
  EvidenceOptions evidence;
  std::string evidence_name = "onehot";
  bool synthetic = false;
  NoiseModel noise;
  bool render = true;
  bool quiet = false;
  size_t autosave_every = 0;
  LocalMapOptions local_map;
  std::shared_ptr<const Calibration> calibration;
};

void runMap(const MapOptions& o) {
  const ClassTable classes = ClassTable::load(o.classes);
  EvidenceOptions ev = o.evidence;
  finishEvidenceOptions(o.evidence_name, o.classes, classes, &ev);
  const Dataset dataset = Dataset::open(o.data, classes, ev.conversion);
  ev.files = dataset.describeEvidenceFiles();
  const bool needs_predictions = ev.source != EvidenceSource::kFile;
  if (needs_predictions && !dataset.hasPredictions() && !o.synthetic) {
    throw std::runtime_error(o.data + ": no predictions/ to derive '" + o.evidence_name +
                             "' evidence from; pass --synthetic-predictions (GT with the "
                             "documented noise model) or use --evidence file with evidence/ "
                             "or alpha/ files");
  }
  std::vector<Scan> scans = loadScans(dataset, o.scans, !o.quiet);
  std::string predictions_note;
  if (o.synthetic) predictions_note = useSyntheticPredictions(&scans, classes, o.noise);
  const Protocol protocol = makeProtocol(o.protocol, scans.size());
  SemanticConfig config = o.config;
  useCalibration(o.calibration, classes, &config);
  warnIfUncalibrated(ev, o.calibration && o.calibration->error_model);
  const auto evidence =
      deriveEvidenceFor(scans, protocol.map_scans, ev, classes, protocol.query_scans);
  Autosave autosave;
  if (o.autosave_every > 0) {
    makeDirectories(o.out);
    autosave = {o.out + "/map.autosave.ot", o.autosave_every};
  }
  LocalMapOptions local_map = o.local_map;
  if (local_map.tile_directory.empty()) local_map.tile_directory = o.out + "/tiles";
  MapRun run = runMapping(scans, protocol.map_scans, evidence, classes, config, o.resolution,
                          !o.quiet, "mapping", autosave, local_map);
  if (o.calibration) applyCalibration(*o.calibration, run.tree.get());
  std::vector<float> query_evidence;
  const std::vector<Query> queries =
      buildQueries(scans, protocol.query_scans, classes.ignore_class, &evidence, &query_evidence);

  RunReport r;
  r.dataset = o.data;
  r.protocol = protocol.name;
  for (size_t s : protocol.map_scans) r.map_scans.push_back(scans[s].name);
  for (size_t s : protocol.query_scans) r.query_scans.push_back(scans[s].name);
  r.variant = variantName(config);
  r.evidence_source = evidenceSourceName(ev.source);
  r.evidence_description = describeEvidence(ev);
  r.evidence_derived = derivedFromHardLabels(ev.source);
  r.evidence_kind = evidenceKind(ev.source);
  r.predictions_note = predictions_note;
  r.config = run.tree->config();
  r.resolution = o.resolution;
  r.map = evaluateMap(*run.tree, queries, classes.ignore_class);
  r.input = evaluateInput(queries, query_evidence, classes.numClasses(), classes.ignore_class);
  r.input_description = inputDescription(ev);
  r.occupied_without_endpoint = static_cast<long long>(
      occupiedWithoutEndpoint(*run.tree, endpointKeys(scans, protocol.map_scans, o.resolution)));
  r.ms_per_scan = run.ms_per_scan;
  r.totals = run.total;
  fillTreeStats(*run.tree, &r);

  makeDirectories(o.out);
  saveMap(*run.tree, o.out + "/map.ot");
  writeText(o.out + "/metrics.json", toJson(r, classes).dump(2) + "\n");
  const std::string md = toMarkdown(r, classes);
  writeText(o.out + "/metrics.md", md);
  if (o.render) {
    const TopDownGrid grid = makeGrid(*run.tree, &queries);
    auto caption = [&](const std::string& what) {
      return captionLines(what, r.variant, r.evidence_description, r.evidence_kind, r.protocol,
                          r.predictions_note);
    };
    writePng(o.out + "/semantic.png",
             renderSemantic(*run.tree, classes, grid, caption("semantic map")));
    writePng(o.out + "/uncertainty.png",
             renderUncertainty(*run.tree, grid,
                               caption(run.tree->errorModel()
                                           ? "error probability, calibrated error model"
                                           : "error probability = 1 - max p (uncalibrated)")));
    writePng(o.out + "/error.png",
             renderError(*run.tree, queries, grid, caption("errors of the GT queries")));
    writePng(o.out + "/quality.png",
             renderQualityCurves(r.map.quality, r.input,
                                 caption("does the uncertainty flag the errors?")));
  }
  std::cout << md << "\nwrote " << o.out << "/{map.ot,metrics.json,metrics.md"
            << (o.render ? ",semantic.png,uncertainty.png,error.png,quality.png" : "") << "}\n";
}

}  // namespace

void addMapCommand(CLI::App& app) {
  auto o = std::make_shared<MapOptions>();
  CLI::App* cmd = app.add_subcommand(
      "map",
      "Map a SemanticKITTI-layout sequence (velodyne/, labels/, predictions/ or evidence/, "
      "poses.txt, calib.txt) or one pose-less scan; write map.ot, metrics.json, metrics.md, "
      "semantic.png, uncertainty.png, error.png, quality.png (error-vs-uncertainty curves and "
      "reliability diagram)");
  addDataOptions(cmd, &o->data, "Dataset directory (or a single .bin scan)", &o->classes);
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--autosave-every", o->autosave_every,
                  "Write the map so far to <out>/map.autosave.ot (atomically) every N mapped "
                  "scans; 0: never")
      ->capture_default_str();
  cmd->add_option("--local-radius", o->local_map.radius,
                  "Keep only the map within this radius [m] of the sensor in memory, the rest as "
                  "tiles in --tile-dir, merged into map.ot at the end (0: the whole map in memory; "
                  "needs --max-range; radius >= max range + 12 voxels)")
      ->capture_default_str();
  cmd->add_option("--tile-dir", o->local_map.tile_directory,
                  "Directory of the local map's tiles (default <out>/tiles; must hold no tiles)");
  cmd->add_option("--protocol", o->protocol,
                  "reconstruction (query the mapped scans) or held-out (map the first half, "
                  "query the second)")
      ->check(CLI::IsMember({"reconstruction", "held-out"}))
      ->capture_default_str();
  cmd->add_option("--scans", o->scans, "Use only the first N scans (0: all)")
      ->capture_default_str();
  addConfigOptions(cmd, &o->config, &o->resolution);
  addCalibrationOption(cmd, &o->calibration);
  addEvidenceOptions(cmd, &o->evidence, &o->evidence_name);
  cmd->add_flag("--synthetic-predictions", o->synthetic,
                "Replace predictions by GT corrupted with the synthetic noise model (for data "
                "without predictions, e.g. RELLIS-3D)");
  cmd->add_option("--noise-point-rate", o->noise.point_rate, "Synthetic point-noise rate")
      ->capture_default_str();
  cmd->add_option("--noise-region-rate", o->noise.region_rate, "Synthetic region-flip rate")
      ->capture_default_str();
  cmd->add_option("--noise-seed", o->noise.seed, "Synthetic noise seed")->capture_default_str();
  cmd->add_flag("!--no-render", o->render, "Skip the PNG renders");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress bars");
  cmd->callback([o]() { runMap(*o); });
}

}  // namespace evidential_octomap::tools
