// `evidential_octomap compare`: every fusion rule and the paper's Table II ablation on the same
// data, evidence and queries; one markdown table per dataset/protocol, plus JSON. Also the
// RELLIS-3D scan with synthetic noisy predictions (off-road class set).
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "bootstrap_report.h"
#include "commands.h"
#include "dataset.h"
#include "evidential_octomap/settings.h"
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
  std::vector<std::string> variants{"dempster",
                                    "dempster-paper",
                                    "dempster-no-adaptive",
                                    "dempster-no-threshold",
                                    "dempster-no-both",
                                    "dempster-no-cap",
                                    "dempster-centre",
                                    "dempster-other-downsampling",
                                    "reference_compat",
                                    "sbki",
                                    "ebs"};
  std::string rellis_data, rellis_classes;
  bool no_rellis = false;
  NoiseModel noise;
  SemanticConfig base;
  double resolution = 0.2;
  EvidenceOptions evidence;
  bool quiet = false;
  BootstrapSettings bootstrap;
  std::string plan = "default";
  bool explicit_selection = false;  // --sources/--variants/--protocols given: full cross product
};

// The paper's Table II rows are named relative to the paper's method (adaptive length and
// threshold both on), whatever the defaults: dempster-no-both is the default's kernel.
SemanticConfig namedVariantConfig(const std::string& v, SemanticConfig c) {
  const auto paper = [&c](bool adaptive, bool threshold) {
    c.rule = "dempster";
    c.adaptive_length = adaptive;
    c.uncertainty_threshold = threshold;
  };
  if (v == "dempster") {
    c.rule = "dempster";
  } else if (v == "dempster-paper") {
    paper(true, true);
  } else if (v == "dempster-no-adaptive") {
    paper(false, true);
  } else if (v == "dempster-no-threshold") {
    paper(true, false);
  } else if (v == "dempster-no-both") {
    paper(false, false);
  } else if (v == "dempster-no-cap") {  // Dempster's product read as is
    c.rule = "dempster";
    c.evidence_cap = 0.0;
  } else if (v == "dempster-centre") {  // kernel distance to voxel centres (a point can miss
    c.rule = "dempster";                // its own voxel)
    c.kernel_distance = "centre";
  } else if (v == "dempster-other-downsampling") {
    c.rule = "dempster";
    c.downsampling = c.downsampling == "average" ? "count_cap" : "average";
  } else if (v == "reference_compat") {  // the authors' released code: no cap either
    c.rule = "dempster";
    c.reference_compat = true;
    c.evidence_cap = 0.0;
  } else if (v == "sbki" || v == "ebs") {
    c.rule = v;
  } else {
    throw std::invalid_argument("unknown variant '" + v + "'");
  }
  return c;
}

// A variant is a named one, optionally followed by parameter overrides that make an ablation
// row: "dempster:drop_percent=0:evidence_cap=2". Throws std::invalid_argument.
SemanticConfig variantConfig(const std::string& variant, const SemanticConfig& base) {
  std::vector<std::string> parts;
  std::stringstream in(variant);
  for (std::string part; std::getline(in, part, ':');) parts.push_back(part);
  if (parts.empty()) throw std::invalid_argument("empty variant");
  SemanticConfig c = namedVariantConfig(parts[0], base);
  for (size_t i = 1; i < parts.size(); ++i) {
    const size_t eq = parts[i].find('=');
    const std::string key = parts[i].substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : parts[i].substr(eq + 1);
    const Setting* setting = findSetting(key);
    if (!setting || !setting->parse(value, &c)) {
      throw std::invalid_argument("variant '" + variant + "': cannot set '" + parts[i] +
                                  "' (key=value of a setting of docs/parameters.md; booleans "
                                  "0/1 or false/true)");
    }
  }
  const std::string problem = c.problem();
  if (!problem.empty()) throw std::invalid_argument("variant '" + variant + "': " + problem);
  return c;
}

// Plans. default (the demo; about 10 min on 2 cores): every variant with onehot evidence (the
// peers' setup); dempster and dempster-paper for knn-vote and confusion
// (what each source does to the paper's uncertainty mechanisms); held-out: dempster, sbki, ebs with
// onehot. extended: also sbki and ebs with knn-vote and confusion. full: every variant x source x
// protocol. Giving --sources/--variants/--protocols runs exactly their cross product.
std::vector<std::string> plannedVariants(const CompareOptions& o, const std::string& protocol,
                                         const std::string& source) {
  if (o.plan == "full" || o.explicit_selection) return o.variants;
  if (protocol == "held-out") {
    return source == "onehot" ? std::vector<std::string>{"dempster", "sbki", "ebs"}
                              : std::vector<std::string>{};
  }
  if (source == "onehot") return o.variants;
  if (o.plan == "extended") return {"dempster", "dempster-paper", "sbki", "ebs"};
  return {"dempster", "dempster-paper"};
}

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
  return {name, bootstrap.scores(outcomes)};
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

// Runs every variant and evidence source on one dataset/protocol; appends rows and JSON.
void runSection(const CompareOptions& o, const std::string& dataset_label,
                const std::string& data_path, const ClassTable& classes,
                const std::vector<Scan>& scans, const std::string& protocol_name,
                const std::vector<std::string>& sources, const std::string& predictions_note,
                std::vector<Section>* sections, nlohmann::json* json,
                nlohmann::json* bootstrap_json) {
  const Protocol protocol = makeProtocol(protocol_name, scans.size());
  const std::vector<Query> queries =
      buildQueries(scans, protocol.query_scans, classes.ignore_class);
  const int num_classes = classes.numClasses();
  const BootstrapReport bootstrap(queries, num_classes, classes.ignore_class, o.bootstrap);
  const nlohmann::json context = {{"dataset_label", dataset_label}, {"protocol", protocol.name}};
  Section sec;
  std::ostringstream title;
  title << dataset_label << ", protocol **" << protocol.name << "**: map scans "
        << scans[protocol.map_scans.front()].name << "–" << scans[protocol.map_scans.back()].name
        << ", query scans " << scans[protocol.query_scans.front()].name << "–"
        << scans[protocol.query_scans.back()].name << " (" << queries.size()
        << " GT-labelled points, class " << classes.names[classes.ignore_class] << " excluded)";
  sec.title = title.str();
  if (!predictions_note.empty()) sec.notes.push_back("Predictions: " + predictions_note + ".");
  sec.notes.push_back(bootstrap.describe() + ".");
  std::vector<QueryOutcome> outcomes;
  const QualityMetrics hard =
      evaluateInput(queries, {}, num_classes, classes.ignore_class, &outcomes);
  sec.rows.push_back("| – | input predictions (hard labels), per point | | |" +
                     qualityCells(hard, NAN, NAN) + " – | – | – |");
  std::vector<ScoredRow> shared_rows{
      {"input predictions (hard labels)", bootstrap.scores(outcomes)}};
  for (ScoredRow& r : addReferenceRows(scans, protocol, queries, classes, o.resolution,
                                       o.base.maxSupportLength(), bootstrap, &sec)) {
    shared_rows.push_back(std::move(r));
  }

  for (const std::string& source_name : sources) {
    const std::vector<std::string> variants = plannedVariants(o, protocol.name, source_name);
    if (variants.empty()) continue;
    EvidenceOptions ev = o.evidence;
    ev.source = evidenceSourceFromName(source_name);
    std::vector<std::vector<float>> evidence;
    try {
      evidence = deriveEvidenceFor(scans, protocol.map_scans, ev, classes, protocol.query_scans);
    } catch (const std::exception& e) {
      sec.notes.push_back("Evidence source " + source_name + " skipped: " + e.what() + ".");
      continue;
    }
    sec.notes.push_back("Evidence `" + source_name + "`: " + describeEvidence(ev) + ".");
    std::vector<float> query_evidence;
    buildQueries(scans, protocol.query_scans, classes.ignore_class, &evidence, &query_evidence);
    const QualityMetrics input =
        evaluateInput(queries, query_evidence, num_classes, classes.ignore_class, &outcomes);
    std::vector<ScoredRow> scored = shared_rows;
    scored.push_back({"input " + source_name + " evidence, per point", bootstrap.scores(outcomes)});
    sec.rows.push_back("| " + source_name + " | " + inputDescription(ev) + " | | |" +
                       qualityCells(input, NAN, NAN) + " – | – | – |");
    sec.detection_rows.push_back("| " + source_name + " | " + inputDescription(ev) + " | | |" +
                                 detectionCells(input));
    const std::vector<octomap::OcTreeKey> endpoints =
        endpointKeys(scans, protocol.map_scans, o.resolution);
    for (const std::string& v : variants) {
      const SemanticConfig config = variantConfig(v, o.base);
      MapRun run = runMapping(scans, protocol.map_scans, evidence, classes, config, o.resolution,
                              !o.quiet, protocol.name + " " + source_name + " " + v);
      RunReport r;
      r.dataset = data_path;
      r.protocol = protocol.name;
      for (size_t s : protocol.map_scans) r.map_scans.push_back(scans[s].name);
      for (size_t s : protocol.query_scans) r.query_scans.push_back(scans[s].name);
      r.variant = variantName(config);
      r.evidence_source = source_name;
      r.evidence_description = describeEvidence(ev);
      r.evidence_derived = derivedFromHardLabels(ev.source);
      r.evidence_kind = evidenceKind(ev.source);
      r.predictions_note = predictions_note;
      r.config = config;
      r.resolution = o.resolution;
      r.map = evaluateMap(*run.tree, queries, classes.ignore_class, &outcomes);
      scored.push_back({v, bootstrap.scores(outcomes)});
      r.input = input;
      r.input_description = inputDescription(ev);
      r.occupied_without_endpoint =
          static_cast<long long>(occupiedWithoutEndpoint(*run.tree, endpoints));
      r.ms_per_scan = run.ms_per_scan;
      r.totals = run.total;
      fillTreeStats(*run.tree, &r);
      const double dropped = r.totals.points_in
                                 ? double(r.totals.points_dropped_uncertain) /
                                       double(r.totals.points_in - r.totals.points_skipped -
                                              r.totals.points_beyond_range)
                                 : 0.0;
      const std::string lead = "| " + source_name + " | " + v + " |" + ablationMarks(config);
      std::ostringstream row;
      row << lead << qualityCells(r.map.quality, r.map.semantic_coverage, r.map.occupancy_coverage)
          << " " << fixed(median(r.ms_per_scan), 0) << " | " << percent(dropped) << " | "
          << lostClasses(r, classes) << " |";
      sec.rows.push_back(row.str());
      sec.detection_rows.push_back(lead + detectionCells(r.map.quality));
      nlohmann::json j = toJson(r, classes);
      j["dataset_label"] = dataset_label;
      j["variant_id"] = v;
      json->push_back(j);
      if (!o.quiet) std::cerr << row.str() << "\n";
    }
    addBootstrapRows(source_name, scored, bootstrap, context, &sec, bootstrap_json);
  }
  sections->push_back(sec);
}

void runCompare(const CompareOptions& o) {
  nlohmann::json runs = nlohmann::json::array(), bootstrap = nlohmann::json::array();
  std::vector<Section> sections;

  const ClassTable classes = ClassTable::load(o.classes);
  const Dataset dataset = Dataset::open(o.data, classes);
  const std::vector<Scan> scans = loadScans(dataset, o.scans, !o.quiet);
  std::vector<std::string> sources = o.sources;
  CompareOptions with_model = o;  // --evidence learned: the model beside the class table
  if (with_model.evidence.learned_model.empty()) {
    with_model.evidence.learned_model = defaultLearnedModel(o.classes, classes);
  }
  const std::string label =
      fs::path(o.data).filename().string() +
      (fs::path(o.data).filename().empty() ? fs::path(o.data).parent_path().filename().string()
                                           : "");
  for (const std::string& p : o.protocols) {
    if (p == "held-out" && scans.size() < 2) continue;
    runSection(with_model, label, o.data, classes, scans, p, sources, "", &sections, &runs,
               &bootstrap);
  }

  std::string rellis_note;
  if (!o.no_rellis) {
    std::string rdata = o.rellis_data, rclasses = o.rellis_classes;
    if (rdata.empty()) {
      rdata =
          (fs::path(o.data).lexically_normal().parent_path() / "rellis3d_example_000104").string();
      if (fs::path(o.data).filename().empty()) {
        rdata = (fs::path(o.data).parent_path().parent_path() / "rellis3d_example_000104").string();
      }
    }
    if (rclasses.empty()) {
      rclasses = (fs::path(o.classes).parent_path() / "classes_rellis3d.yaml").string();
    }
    if (fs::exists(rdata) && fs::exists(rclasses)) {
      const ClassTable rtable = ClassTable::load(rclasses);
      const Dataset rset = Dataset::open(rdata, rtable);
      std::vector<Scan> rscans = loadScans(rset, 0, !o.quiet);
      useSyntheticPredictions(&rscans, rtable, o.noise);
      std::vector<std::string> rsources;
      for (const auto& s : o.sources)
        if (s != "confusion" && s != "file" && s != "learned") rsources.push_back(s);
      runSection(o,
                 "RELLIS-3D " + fs::path(rdata).filename().string() +
                     " (single scan, identity pose, SYNTHETIC predictions)",
                 rdata, rtable, rscans, "reconstruction", rsources, o.noise.describe(), &sections,
                 &runs, &bootstrap);
      sections.back().notes.push_back(
          "Evidence `confusion` is not run here: one scan leaves no other scan to estimate the "
          "confusion matrix on; `learned` neither (no model is trained for this class set, "
          "and one scan cannot be cross-fitted).");
    } else {
      rellis_note = "RELLIS-3D part skipped: " + rdata + " or " + rclasses + " not found.";
    }
  }

  std::ostringstream md;
  md << "# compare: fusion rules and the Table II ablation on the same queries\n\n"
     << "Metrics (include/evidential_octomap/metrics.h), the same queries (GT-labelled points) "
        "for every row: mIoU / Acc over **all** queries (a query whose voxel holds no evidence "
        "counts as wrong) and over labelled ones; sem. cov. = share of queries whose voxel holds "
        "evidence (the paper's O.Acc); occ. cov. = share whose voxel is occupied; Brier = mean "
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
     << (o.explicit_selection ? std::string("the --sources/--variants/--protocols given")
                              : "--plan " + o.plan + " (see compare --help)")
     << ".\n\n";
  for (const Section& s : sections) {
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

  makeDirectories(o.out);
  writeText(o.out + "/compare.md", md.str());
  nlohmann::json all;
  all["runs"] = runs;
  all["bootstrap"] = bootstrap;
  writeText(o.out + "/compare.json", all.dump(2) + "\n");
  std::cout << md.str() << "wrote " << o.out << "/{compare.md,compare.json}\n";
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
  cmd->add_option("--sources", o->sources,
                  "Evidence sources (file, onehot, knn-vote, confusion, learned)")
      ->delimiter(',')
      ->check(CLI::IsMember({"file", "onehot", "knn-vote", "confusion", "learned"}))
      ->capture_default_str();
  cmd->add_option("--protocols", o->protocols, "reconstruction and/or held-out")
      ->delimiter(',')
      ->check(CLI::IsMember({"reconstruction", "held-out"}))
      ->capture_default_str();
  cmd->add_option("--variants", o->variants,
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
  cmd->add_option("--plan", o->plan,
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
  cmd->callback([o, cmd]() {
    o->explicit_selection =
        cmd->count("--sources") + cmd->count("--variants") + cmd->count("--protocols") > 0;
    runCompare(*o);
  });
}

}  // namespace evidential_octomap::tools
