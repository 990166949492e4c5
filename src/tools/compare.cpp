// `evidential_octomap compare`: every fusion rule and the paper's Table II ablation on the same
// data, evidence and queries; one markdown table per dataset/protocol, plus JSON. Also the
// RELLIS-3D scan with synthetic noisy predictions (off-road class set).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "bootstrap_report.h"
#include "commands.h"
#include "compare_variants.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "pipeline.h"
#include "report.h"
#include "synthetic.h"
#include "voxel_majority.h"

namespace fs = std::filesystem;

namespace evidential_octomap::tools {

namespace {

struct CompareOptions {
  std::string data, classes, out = "out/compare";
  size_t scans = 0;
  std::vector<std::string> sources{"onehot", "knn-vote", "confusion"};
  std::vector<std::string> protocols{"reconstruction", "held-out"};
  RunPlan plan;  // the variants, and which of them each source and protocol runs
  std::string rellis_data, rellis_classes;
  bool no_rellis = false;
  NoiseModel noise;
  SemanticConfig base;
  double resolution = 0.2;
  EvidenceOptions evidence;
  bool quiet = false;
  BootstrapSettings bootstrap;
  std::shared_ptr<const Calibration> calibration;  // adds a dempster+calibration row
};

struct Section {
  std::string title;
  std::vector<std::string> notes;
  std::vector<std::string> rows;            // accuracy and calibration
  std::vector<std::string> detection_rows;  // error detection
  std::vector<std::string> bootstrap_rows;  // each row against default dempster
};

// A row kept for the paired bootstrap: its name and block statistics.
struct ScoredRow {
  std::string name;
  BlockScores scores;
  std::vector<double> iou{};  // per class over all queries (reference rows only)
};

// One reference row: metrics of the answers, a table row and its block scores.
ScoredRow referenceRow(const std::vector<Query>& answered, const std::string& name,
                       const ClassTable& classes, const BootstrapReport& bootstrap, Section* sec) {
  std::vector<QueryOutcome> outcomes;
  const QualityMetrics q =
      evaluateInput(answered, {}, classes.numClasses(), classes.ignore_class, &outcomes);
  sec->rows.push_back("| – | " + name + " | | |" +
                      qualityCells(q, q.queries ? double(q.labelled) / q.queries : NAN, NAN) +
                      " – | – | – |");
  std::vector<double> iou(classes.numClasses());
  for (int c = 0; c < classes.numClasses(); ++c) iou[c] = q.all.iou(c);
  return {name, bootstrap.scores(outcomes), iou};
}

// The reference rows of voxel_majority.h (no rule): the majority of the mapped points'
// predictions, and of their GT, in each query's voxel; and the neighbourhood oracle of the
// predictions within the kernel's largest support.
std::vector<ScoredRow> addReferenceRows(const std::vector<Scan>& scans, const Protocol& protocol,
                                        const std::vector<Query>& queries,
                                        const ClassTable& classes, double resolution,
                                        double support, const BootstrapReport& bootstrap,
                                        Section* sec) {
  std::vector<ScoredRow> out;
  const std::pair<MajorityOf, const char*> kinds[] = {
      {MajorityOf::kPredictions, "voxel majority of the mapped points' predictions (reference)"},
      {MajorityOf::kGroundTruth, "voxel majority of the mapped points' GT (resolution ceiling)"}};
  for (const auto& [what, name] : kinds) {
    out.push_back(
        referenceRow(voxelMajorityAnswers(scans, protocol.map_scans, queries, resolution,
                                          classes.numClasses(), classes.ignore_class, what),
                     name, classes, bootstrap, sec));
  }
  std::ostringstream name;
  name << "oracle: GT when a mapped point within " << std::fixed << std::setprecision(2) << support
       << " m predicts it (upper bound for one-hot evidence)";
  out.push_back(
      referenceRow(neighbourhoodOracleAnswers(scans, protocol.map_scans, queries, resolution,
                                              support, classes.numClasses(), classes.ignore_class),
                   name.str(), classes, bootstrap, sec));
  return out;
}

// Every scored row of one evidence source against its `dempster` run (when there is one).
void addBootstrapRows(const std::string& source, const std::vector<ScoredRow>& rows,
                      const BootstrapReport& bootstrap, const nlohmann::json& context, Section* sec,
                      nlohmann::json* json) {
  const auto reference = std::find_if(rows.begin(), rows.end(),
                                      [](const ScoredRow& r) { return r.name == "dempster"; });
  if (reference == rows.end()) return;
  for (const ScoredRow& r : rows) {
    if (&r == &*reference) continue;
    bootstrap.compare(source, r.name, r.scores, reference->scores, context, &sec->bootstrap_rows,
                      json);
  }
}

const char* kLead = " evidence | method | Adap. | Thr. |";
const char* kTail = " ms/scan | dropped % | classes lost (map IoU 0, input > 0) |";

std::string tableHeader() {
  std::string h = qualityHeader(kLead);
  const size_t eol = h.find('\n');
  return h.substr(0, eol) + kTail + "\n" + h.substr(eol + 1, h.size() - eol - 2) + "---|---|---|\n";
}

// Classes present in GT whose map IoU is 0 although the input's is not: what the percentile
// threshold (or the kernel) wiped out.
std::string lostClasses(const RunReport& r, const ClassTable& classes) {
  std::string out;
  const QualityMetrics& q = r.map.quality;
  for (int c = 0; c < classes.numClasses(); ++c) {
    if (c == classes.ignore_class || !q.all.presentInGt(c)) continue;
    if (q.all.iou(c) == 0.0 && r.input.all.iou(c) > 0.0) {
      out += (out.empty() ? "" : ", ") + classes.names[c];
    }
  }
  return out.empty() ? "–" : out;
}

std::string ablationMarks(const SemanticConfig& config) {
  const bool dst = config.rule == "dempster";
  const bool thr = dst || config.rule == "ebs";
  const bool adaptive = thr && config.effectiveGamma() != 0.0;
  return std::string(" ") + (thr ? (adaptive ? "✓" : "") : "–") + " | " +
         (thr ? (config.uncertainty_threshold && config.drop_percent > 0.0 ? "✓" : "") : "–") +
         " |";
}

// One dataset: its scans and class table, as one section's rows name them.
struct SectionData {
  std::string label, path;  // e.g. "semantickitti_08_first10"; the path given
  const ClassTable* classes = nullptr;
  const std::vector<Scan>* scans = nullptr;
  std::vector<std::string> sources;
  std::string predictions_note;  // synthetic predictions: how they were made
};

// What compare writes: one section per dataset and protocol, every run and bootstrap in JSON.
struct CompareResults {
  std::vector<Section> sections;
  nlohmann::json runs = nlohmann::json::array(), bootstrap = nlohmann::json::array();
};

// The dropped share of a run's points (above the percentile threshold).
double droppedShare(const InsertStats& t) {
  return t.points_in ? double(t.points_dropped_uncertain) /
                           double(t.points_in - t.points_skipped - t.points_beyond_range)
                     : 0.0;
}

// Every variant and evidence source on one dataset and protocol: one Section of rows and JSON.
class SectionRun {
 public:
  SectionRun(const CompareOptions& o, const SectionData& data, const std::string& protocol_name)
      : o_(o),
        data_(data),
        classes_(*data.classes),
        scans_(*data.scans),
        protocol_(makeProtocol(protocol_name, scans_.size())),
        queries_(buildQueries(scans_, protocol_.query_scans, classes_.ignore_class)),
        bootstrap_(queries_, classes_.numClasses(), classes_.ignore_class, o.bootstrap),
        context_({{"dataset_label", data.label}, {"protocol", protocol_.name}}) {}

  void run(CompareResults* out) {
    sec_.title = title();
    if (!data_.predictions_note.empty())
      sec_.notes.push_back("Predictions: " + data_.predictions_note + ".");
    sec_.notes.push_back(bootstrap_.describe() + ".");
    addSharedRows();
    for (const std::string& source : data_.sources) runSource(source, out);
    out->sections.push_back(sec_);
  }

 private:
  std::string title() const {
    std::ostringstream t;
    t << data_.label << ", protocol **" << protocol_.name << "**: map scans "
      << scans_[protocol_.map_scans.front()].name << "–"
      << scans_[protocol_.map_scans.back()].name << ", query scans "
      << scans_[protocol_.query_scans.front()].name << "–"
      << scans_[protocol_.query_scans.back()].name << " (" << queries_.size()
      << " GT-labelled points, class " << classes_.names[classes_.ignore_class] << " excluded)";
    return t.str();
  }

  // The rows without evidence: the input's hard labels and the reference rows.
  void addSharedRows() {
    std::vector<QueryOutcome> outcomes;
    const QualityMetrics hard =
        evaluateInput(queries_, {}, classes_.numClasses(), classes_.ignore_class, &outcomes);
    sec_.rows.push_back("| – | input predictions (hard labels), per point | | |" +
                        qualityCells(hard, NAN, NAN) + " – | – | – |");
    shared_rows_ = {{"input predictions (hard labels)", bootstrap_.scores(outcomes)}};
    for (ScoredRow& r : addReferenceRows(scans_, protocol_, queries_, classes_, o_.resolution,
                                         o_.base.maxSupportLength(), bootstrap_, &sec_)) {
      shared_rows_.push_back(std::move(r));
    }
    majority_iou_ = shared_rows_[1].iou;  // the voxel majority of the predictions
  }

  void runSource(const std::string& source, CompareResults* out) {
    const std::vector<std::string> variants = o_.plan.variantsFor(protocol_.name, source);
    if (variants.empty()) return;
    EvidenceOptions ev = o_.evidence;
    ev.source = evidenceSourceFromName(source);
    std::vector<std::vector<float>> evidence;
    try {
      evidence =
          deriveEvidenceFor(scans_, protocol_.map_scans, ev, classes_, protocol_.query_scans);
    } catch (const std::exception& e) {
      sec_.notes.push_back("Evidence source " + source + " skipped: " + e.what() + ".");
      return;
    }
    sec_.notes.push_back("Evidence `" + source + "`: " + describeEvidence(ev) + ".");
    std::vector<float> query_evidence;
    buildQueries(scans_, protocol_.query_scans, classes_.ignore_class, &evidence, &query_evidence);
    std::vector<QueryOutcome> outcomes;
    const QualityMetrics input = evaluateInput(queries_, query_evidence, classes_.numClasses(),
                                               classes_.ignore_class, &outcomes);
    std::vector<ScoredRow> scored = shared_rows_;
    scored.push_back({"input " + source + " evidence, per point", bootstrap_.scores(outcomes)});
    sec_.rows.push_back("| " + source + " | " + inputDescription(ev) + " | | |" +
                        qualityCells(input, NAN, NAN) + " – | – | – |");
    addSourceMajorityRow(source, evidence, &scored);
    sec_.detection_rows.push_back("| " + source + " | " + inputDescription(ev) + " | | |" +
                                  detectionCells(input));
    const std::vector<octomap::OcTreeKey> endpoints =
        endpointKeys(scans_, protocol_.map_scans, o_.resolution);
    for (const std::string& v : variants) {
      runVariant(source, ev, evidence, input, endpoints, v, &scored, out);
    }
    addBootstrapRows(source, scored, bootstrap_, context_, &sec_, &out->bootstrap);
  }

  // The voxel majority of the source's own per-point labels (the argmax of its evidence), the
  // bound that resolution sets on "no class below the input's IoU" for this source. A row of its
  // own only where those labels are not the predictions (learned evidence, a network's).
  void addSourceMajorityRow(const std::string& source,
                            const std::vector<std::vector<float>>& evidence,
                            std::vector<ScoredRow>* scored) {
    const std::vector<std::vector<int>> labels = evidenceLabels(evidence, classes_.numClasses());
    source_majority_iou_ = majority_iou_;
    if (std::all_of(protocol_.map_scans.begin(), protocol_.map_scans.end(),
                    [&](size_t s) { return labels[s] == scans_[s].predicted; }))
      return;
    ScoredRow row = referenceRow(
        voxelMajorityAnswers(scans_, labels, protocol_.map_scans, queries_, o_.resolution,
                             classes_.numClasses(), classes_.ignore_class),
        "voxel majority of the mapped points' " + source + " labels (argmax of the evidence)",
        classes_, bootstrap_, &sec_);
    source_majority_iou_ = row.iou;
    scored->push_back(std::move(row));
  }

  // One map: its rows; with --calibration, default dempster's map read with the file is a row
  // of its own ("dempster+calibration").
  void runVariant(const std::string& source, const EvidenceOptions& ev,
                  const std::vector<std::vector<float>>& evidence, const QualityMetrics& input,
                  const std::vector<octomap::OcTreeKey>& endpoints, const std::string& v,
                  std::vector<ScoredRow>* scored, CompareResults* out) {
    const SemanticConfig config = variantConfig(v, o_.base);
    MapRun run = runMapping(scans_, protocol_.map_scans, evidence, classes_, config,
                            o_.resolution, !o_.quiet, protocol_.name + " " + source + " " + v);
    scored->push_back(scoreMap(source, ev, input, endpoints, v, run, out));
    if (v != "dempster" || !o_.calibration) return;
    const std::string problem = o_.calibration->problemWith(classes_.names, config.rule);
    if (!problem.empty()) {
      sec_.notes.push_back("No dempster+calibration row: " + problem + ".");
      return;
    }
    applyCalibration(*o_.calibration, run.tree.get());
    scored->push_back(scoreMap(source, ev, input, endpoints, "dempster+calibration", run, out));
  }

  // A map's report (JSON), its table rows, its block scores for the bootstrap.
  ScoredRow scoreMap(const std::string& source, const EvidenceOptions& ev,
                     const QualityMetrics& input,
                     const std::vector<octomap::OcTreeKey>& endpoints, const std::string& v,
                     const MapRun& run, CompareResults* out) {
    const SemanticConfig& config = run.tree->config();
    std::vector<QueryOutcome> outcomes;
    RunReport r = report(source, ev, config, run);
    r.map = evaluateMap(*run.tree, queries_, classes_.ignore_class, &outcomes);
    r.input = input;
    r.occupied_without_endpoint =
        static_cast<long long>(occupiedWithoutEndpoint(*run.tree, endpoints));
    fillTreeStats(*run.tree, &r);
    const std::string lead = "| " + source + " | " + v + " |" + ablationMarks(config);
    std::ostringstream row;
    row << lead << qualityCells(r.map.quality, r.map.semantic_coverage, r.map.occupancy_coverage)
        << " " << fixed(median(r.ms_per_scan), 0) << " | " << percent(droppedShare(r.totals))
        << " | " << lostClasses(r, classes_) << " |";
    sec_.rows.push_back(row.str());
    sec_.detection_rows.push_back(lead + detectionCells(r.map.quality));
    nlohmann::json j = toJson(r, classes_);
    // What a voxel map of the input's own labels reaches, without any kernel: the bound that
    // resolution sets on "no class below the input's IoU".
    for (auto& c : j["per_class"]) {
      const double iou = source_majority_iou_[c["class"].get<int>()];
      c["voxel_majority_iou"] = std::isfinite(iou) ? nlohmann::json(iou) : nlohmann::json(nullptr);
    }
    j["dataset_label"] = data_.label;
    j["variant_id"] = v;
    out->runs.push_back(j);
    if (!o_.quiet) std::cerr << row.str() << "\n";
    return {v, bootstrap_.scores(outcomes)};
  }

  // What a run is (dataset, protocol, scans, evidence, settings) and how long it took.
  RunReport report(const std::string& source, const EvidenceOptions& ev,
                   const SemanticConfig& config, const MapRun& run) const {
    RunReport r;
    r.dataset = data_.path;
    r.protocol = protocol_.name;
    for (size_t s : protocol_.map_scans) r.map_scans.push_back(scans_[s].name);
    for (size_t s : protocol_.query_scans) r.query_scans.push_back(scans_[s].name);
    r.variant = variantName(config);
    r.evidence_source = source;
    r.evidence_description = describeEvidence(ev);
    r.evidence_derived = derivedFromHardLabels(ev.source);
    r.evidence_kind = evidenceKind(ev.source);
    r.predictions_note = data_.predictions_note;
    r.config = config;
    r.resolution = o_.resolution;
    r.input_description = inputDescription(ev);
    r.ms_per_scan = run.ms_per_scan;
    r.totals = run.total;
    return r;
  }

  const CompareOptions& o_;
  const SectionData& data_;
  const ClassTable& classes_;
  const std::vector<Scan>& scans_;
  const Protocol protocol_;
  const std::vector<Query> queries_;
  const BootstrapReport bootstrap_;
  const nlohmann::json context_;
  Section sec_;
  std::vector<ScoredRow> shared_rows_;
  std::vector<double> majority_iou_;  // per class, the voxel majority of the predictions
  std::vector<double> source_majority_iou_;  // ... of the labels of the source at hand
};

// The RELLIS-3D scan and class table: given, else guessed beside --data and --classes.
std::pair<std::string, std::string> rellisPaths(const CompareOptions& o) {
  std::string data = o.rellis_data, classes = o.rellis_classes;
  if (data.empty()) {
    const fs::path given(o.data);
    data = (given.lexically_normal().parent_path() / "rellis3d_example_000104").string();
    if (given.filename().empty())
      data = (given.parent_path().parent_path() / "rellis3d_example_000104").string();
  }
  if (classes.empty())
    classes = (fs::path(o.classes).parent_path() / "classes_rellis3d.yaml").string();
  return {data, classes};
}

// The RELLIS-3D section (synthetic predictions, reconstruction only); "" or why it was skipped.
std::string runRellis(const CompareOptions& o, CompareResults* out) {
  const auto [data, classes_path] = rellisPaths(o);
  if (!fs::exists(data) || !fs::exists(classes_path))
    return "RELLIS-3D part skipped: " + data + " or " + classes_path + " not found.";
  const ClassTable classes = ClassTable::load(classes_path);
  const Dataset dataset = Dataset::open(data, classes);
  std::vector<Scan> scans = loadScans(dataset, 0, !o.quiet);
  useSyntheticPredictions(&scans, classes, o.noise);
  SectionData section{"RELLIS-3D " + fs::path(data).filename().string() +
                          " (single scan, identity pose, SYNTHETIC predictions)",
                      data, &classes, &scans, {}, o.noise.describe()};
  for (const auto& s : o.sources)
    if (s != "confusion" && s != "file" && s != "learned") section.sources.push_back(s);
  SectionRun(o, section, "reconstruction").run(out);
  out->sections.back().notes.push_back(
      "Evidence `confusion` is not run here: one scan leaves no other scan to estimate the "
      "confusion matrix on; `learned` neither (no model is trained for this class set, "
      "and one scan cannot be cross-fitted).");
  return "";
}

// compare.md: what the columns mean, then every section's tables.
std::string compareMarkdown(const CompareOptions& o, const CompareResults& results,
                            const std::string& rellis_note) {
  std::ostringstream md;
  md << "# compare: fusion rules and the Table II ablation on the same queries\n\n"
     << "Metrics (include/evidential_octomap/evaluation/metrics.h), the same queries (GT-labelled points) "
        "for every row: mIoU / Acc over **all** queries (a query the map does not answer "
        "counts as wrong) and over labelled ones; sem. cov. = share of queries the map answers "
        "(its voxel's evidence; with semantic_occupied_only also the support answer of the "
        "voxels with evidence around a known voxel without any; the paper's O.Acc); occ. cov. = share whose voxel is occupied; Brier = mean "
        "multi-class Brier score of the projected class probabilities (dempster b + u/C, "
        "sbki/ebs alpha/S, no label: uniform), NLL (p clipped at 1e-6), ECE (10 bins); error "
        "detection: AUROC and AURC of each uncertainty output for \"the label is wrong\" among "
        "labelled queries. Input rows: each point's own evidence (or hard label). ms/scan = "
        "median insertSemanticScan wall time (loading and evidence derivation excluded). "
        "dropped % = points above the per-scan percentile threshold. Resolution "
     << o.resolution << " m; every other parameter at its SemanticConfig default unless the "
     << "variant changes it (see compare.json). Evidence `onehot`, `knn-vote` and `confusion` "
        "is **derived from hard labels**; `learned` is a small evidential model's, "
        "**cross-fitted** (no scan's evidence from a model that saw its labels); none is a "
        "full EDL network's. Runs: "
     << (o.plan.explicit_selection ? std::string("the --sources/--variants/--protocols given")
                                   : "--plan " + o.plan.name + " (see compare --help)")
     << ".\n\n";
  for (const Section& s : results.sections) {
    md << "## " << s.title << "\n\n";
    for (const auto& n : s.notes) md << "- " << n << "\n";
    md << "\n" << tableHeader();
    for (const auto& r : s.rows) md << r << "\n";
    md << "\nError detection among labelled queries:\n\n" << detectionHeader(kLead);
    for (const auto& r : s.detection_rows) md << r << "\n";
    if (!s.bootstrap_rows.empty()) {
      md << "\nPaired bootstrap against default `dempster` (Δ = row − dempster; mIoU over all "
            "queries in points, Brier lower is better):\n\n"
         << BootstrapReport::header();
      for (const auto& r : s.bootstrap_rows) md << r << "\n";
    }
    md << "\n";
  }
  if (!rellis_note.empty()) md << rellis_note << "\n";
  return md.str();
}

void runCompare(const CompareOptions& o) {
  CompareResults results;
  const ClassTable classes = ClassTable::load(o.classes);
  const Dataset dataset = Dataset::open(o.data, classes);
  const std::vector<Scan> scans = loadScans(dataset, o.scans, !o.quiet);
  CompareOptions with_model = o;  // --evidence learned: the model beside the class table
  if (with_model.evidence.learned_model.empty()) {
    with_model.evidence.learned_model = defaultLearnedModel(o.classes, classes);
  }
  const fs::path given(o.data);
  const SectionData main_data{
      given.filename().string() +
          (given.filename().empty() ? given.parent_path().filename().string() : ""),
      o.data, &classes, &scans, o.sources, ""};
  for (const std::string& p : o.protocols) {
    if (p == "held-out" && scans.size() < 2) continue;
    SectionRun(with_model, main_data, p).run(&results);
  }
  const std::string rellis_note = o.no_rellis ? "" : runRellis(o, &results);

  const std::string md = compareMarkdown(o, results, rellis_note);
  makeDirectories(o.out);
  writeText(o.out + "/compare.md", md);
  nlohmann::json all;
  all["runs"] = results.runs;
  all["bootstrap"] = results.bootstrap;
  writeText(o.out + "/compare.json", all.dump(2) + "\n");
  std::cout << md << "wrote " << o.out << "/{compare.md,compare.json}\n";
}

// --sources, --protocols, --variants: which runs (their cross product when given).
void addSelectionOptions(CLI::App* cmd, CompareOptions* o) {
  cmd->add_option("--sources", o->sources,
                  "Evidence sources (file, onehot, knn-vote, confusion, learned)")
      ->delimiter(',')
      ->check(CLI::IsMember({"file", "onehot", "knn-vote", "confusion", "learned"}))
      ->capture_default_str();
  cmd->add_option("--protocols", o->protocols, "reconstruction and/or held-out")
      ->delimiter(',')
      ->check(CLI::IsMember({"reconstruction", "held-out"}))
      ->capture_default_str();
  cmd->add_option("--variants", o->plan.variants,
                  "dempster (the defaults), dempster-paper (adaptive length and threshold on), "
                  "dempster-no-adaptive, dempster-no-threshold, dempster-no-both (the paper's "
                  "method without them), "
                  "dempster-no-cap, dempster-centre, dempster-other-downsampling, "
                  "reference_compat, sbki, ebs; each optionally with SemanticConfig overrides, "
                  "e.g. dempster:drop_percent=0:evidence_cap=2 (an ablation row)")
      ->delimiter(',')
      ->check(CLI::Validator(
          [](std::string& v) {
            try {
              variantConfig(v, SemanticConfig());
              return std::string();
            } catch (const std::exception& e) {
              return std::string(e.what());
            }
          },
          "VARIANT[:key=value...]"))
      ->capture_default_str();
}

// The RELLIS-3D part: where its scan and class table are, and its synthetic predictions.
void addRellisOptions(CLI::App* cmd, CompareOptions* o) {
  cmd->add_option("--rellis-data", o->rellis_data,
                  "RELLIS-3D scan directory (default: rellis3d_example_000104 beside --data)");
  cmd->add_option("--rellis-classes", o->rellis_classes,
                  "RELLIS-3D class table (default: classes_rellis3d.yaml beside --classes)");
  cmd->add_flag("--no-rellis", o->no_rellis, "Skip the RELLIS-3D part");
  cmd->add_option("--noise-point-rate", o->noise.point_rate, "Synthetic point-noise rate")
      ->capture_default_str();
  cmd->add_option("--noise-region-rate", o->noise.region_rate, "Synthetic region-flip rate")
      ->capture_default_str();
  cmd->add_option("--noise-seed", o->noise.seed, "Synthetic noise seed")->capture_default_str();
}

// What every run shares: resolution, insert settings, evidence derivation.
void addRunOptions(CLI::App* cmd, CompareOptions* o) {
  cmd->add_option("--resolution", o->resolution, "Voxel size [m]")->capture_default_str();
  cmd->add_option("--max-range", o->base.max_range, "Max sensor range [m] (< 0: unlimited)")
      ->capture_default_str();
  cmd->add_option("--threads", o->base.threads, "Threads of the semantic pass (0: default)")
      ->capture_default_str();
  cmd->add_option("--fast-free-space", o->base.fast_free_space,
                  "Fast free space in every row (not exact; true/false)")
      ->capture_default_str();
  cmd->add_option("-E,--evidence-magnitude", o->evidence.magnitude,
                  "Evidence magnitude E of derived sources")
      ->capture_default_str();
  cmd->add_option("--knn-k", o->evidence.knn_k, "Neighbours voting in knn-vote")
      ->capture_default_str();
  cmd->add_option("--knn-radius", o->evidence.knn_radius, "Neighbour radius of knn-vote [m]")
      ->capture_default_str();
  cmd->add_option("--learned-model", o->evidence.learned_model,
                  "Model file of the learned source (default: <class table dir>/learned/"
                  "<dataset>.model)");
  cmd->add_flag("!--no-calibration", o->evidence.calibrate,
                "Derived evidence as is (no rescaling of u to the error rate of such points)");
}

// The plan, the paired bootstrap and the output.
void addPlanOptions(CLI::App* cmd, CompareOptions* o) {
  cmd->add_option("--plan", o->plan.name,
                  "default: every variant with onehot, dempster and dempster-paper for "
                  "knn-vote and confusion, held-out dempster/sbki/ebs with onehot (~10 min); "
                  "extended: also sbki and ebs for knn-vote and confusion; full: every variant x "
                  "source x protocol")
      ->check(CLI::IsMember({"default", "extended", "full"}))
      ->capture_default_str();
  cmd->add_option("--bootstrap-replicates", o->bootstrap.replicates,
                  "Replicates of the paired bootstrap against default dempster")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--bootstrap-block", o->bootstrap.block_size,
                  "Side [m] of the square x-y blocks the bootstrap resamples")
      ->check(CLI::Range(0.01, 1e6))
      ->capture_default_str();
  cmd->add_option("--bootstrap-seed", o->bootstrap.seed, "Seed of the bootstrap draws")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "No progress bars or per-run lines on stderr");
}

}  // namespace

void addCompareCommand(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Run dempster, its Table II ablations (w/o adaptive length, w/o threshold, w/o both), "
      "reference_compat, sbki and ebs on the same data, evidence and queries; print one "
      "markdown table per dataset/protocol and write compare.md + compare.json. Also runs the "
      "RELLIS-3D scan with synthetic noisy predictions. Each table has two reference rows "
      "without a kernel (the voxel majority of the mapped points' predictions, and of their GT) "
      "and a paired spatial-block bootstrap of every row's mIoU(all) and Brier difference to "
      "default dempster");
  addDataOptions(cmd, &o->data, "SemanticKITTI-layout directory", &o->classes);
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--scans", o->scans, "Use only the first N scans (0: all)")
      ->capture_default_str();
  addSelectionOptions(cmd, o.get());
  addRellisOptions(cmd, o.get());
  addRunOptions(cmd, o.get());
  addPlanOptions(cmd, o.get());
  addCalibrationOption(cmd, &o->calibration);
  cmd->callback([o, cmd]() {
    o->plan.explicit_selection =
        cmd->count("--sources") + cmd->count("--variants") + cmd->count("--protocols") > 0;
    runCompare(*o);
  });
}

}  // namespace evidential_octomap::tools
