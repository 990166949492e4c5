// End to end: the `evidential_octomap` binary on 2 bundled scans, checked against a second,
// independent computation of the metrics in this file (own file parsing, own pose, own loops).
#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/LU>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "test_helpers.h"

namespace fs = std::filesystem;
using namespace tools_test;
using evidential_octomap::ClassTable;
using evidential_octomap::EvidentialOcTree;

namespace {

using Result = CliResult;

Result run(const std::string& args) { return runCli(args); }

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

template <typename T>
std::vector<T> readRaw(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(0, std::ios::end);
  std::vector<T> v(size_t(in.tellg()) / sizeof(T));
  in.seekg(0);
  in.read(reinterpret_cast<char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
  return v;
}

Eigen::Matrix4d parse3x4(const std::string& text) {
  std::istringstream in(text);
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) in >> T(r, c);
  return T;
}

// The metrics of metrics.h recomputed from scratch for scans 000000 and 000001: the map's
// answer at a query is its voxel's label when the voxel holds evidence (dempster payload L read
// with sum L capped at evidence_cap: L' = L min(1, cap / sum L), p^c = (e^{L'^c} - 1 + 1/C) u
// with u = 1 / (sum e^L' - C + 1)), else no label and uniform p.
struct Independent {
  size_t queries = 0, labelled = 0, occupied = 0, correct = 0;
  double brier = 0.0;
  double miou_all = 0.0;
  std::vector<std::vector<size_t>> confusion;  // GT x (predicted, then no label)
};

Independent recompute(const EvidentialOcTree& tree, const ClassTable& classes) {
  std::ifstream calib(kittiDir() + "/calib.txt"), poses(kittiDir() + "/poses.txt");
  std::string line;
  Eigen::Matrix4d Tr;
  while (std::getline(calib, line))
    if (line.rfind("Tr:", 0) == 0) Tr = parse3x4(line.substr(3));
  const int C = classes.numClasses();
  std::vector<size_t> tp(C, 0), fp(C, 0), fn(C, 0);
  Independent r;
  r.confusion.assign(C, std::vector<size_t>(C + 1, 0));
  for (const char* name : {"000000", "000001"}) {
    std::getline(poses, line);
    const Eigen::Matrix4d T = Tr.inverse() * parse3x4(line) * Tr;
    const auto xyzr = readRaw<float>(kittiDir() + "/velodyne/" + name + ".bin");
    const auto labels = readRaw<uint32_t>(kittiDir() + "/labels/" + name + ".label");
    for (size_t i = 0; i < labels.size(); ++i) {
      const int gt = classes.learning_map.at(labels[i] & 0xFFFF);
      if (gt == classes.ignore_class) continue;
      const Eigen::Vector3d p =
          (T * Eigen::Vector4d(xyzr[4 * i], xyzr[4 * i + 1], xyzr[4 * i + 2], 1.0)).head<3>();
      ++r.queries;
      const auto* node = tree.search(float(p.x()), float(p.y()), float(p.z()));
      if (node && node->getLogOdds() >= 0.0f) ++r.occupied;  // occupied: p >= 0.5
      std::vector<long double> prob(C, 1.0L / C);
      int s = -1;
      if (const std::vector<float> raw = tree.payload(node); !raw.empty()) {
        long double total = 0.0L, best = 0.0L;
        for (int c = 0; c < C; ++c) {
          total += raw[c];
          if (raw[c] > best) best = raw[c], s = c;
        }
        const long double cap = tree.effectiveEvidenceCap();
        const long double scale = cap > 0 && total > cap ? cap / total : 1.0L;
        long double sum = 0.0L;
        for (int c = 0; c < C; ++c) sum += std::exp(scale * raw[c]);
        const long double u = 1.0L / (sum - C + 1);
        for (int c = 0; c < C; ++c) prob[c] = (std::exp(scale * raw[c]) - 1 + 1.0L / C) * u;
      }
      for (int c = 0; c < C; ++c) r.brier += double((prob[c] - (c == gt)) * (prob[c] - (c == gt)));
      if (s >= 0) ++r.labelled;
      ++r.confusion[gt][s >= 0 ? s : C];
      if (s == gt) {
        ++r.correct;
        ++tp[gt];
      } else {
        ++fn[gt];
        if (s >= 0) ++fp[s];
      }
    }
  }
  r.brier /= double(r.queries);
  // mIoU over classes present in GT, every query counted (no label = wrong).
  int n = 0;
  for (int c = 0; c < C; ++c) {
    if (c == classes.ignore_class || tp[c] + fn[c] == 0) continue;
    r.miou_all += double(tp[c]) / double(tp[c] + fp[c] + fn[c]);
    ++n;
  }
  r.miou_all /= n;
  return r;
}

class CliEndToEnd : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    out_ = freshDir("cli_e2e");
    map_result_ = run("map --data " + kittiDir() + " --classes " + kittiClasses() +
                      " --scans 2 --quiet --out " + out_ + "/map");
  }
  static std::string out_;
  static Result map_result_;
};
std::string CliEndToEnd::out_;
Result CliEndToEnd::map_result_;

}  // namespace

TEST_F(CliEndToEnd, MapWritesEveryOutput) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  for (const char* f : {"map.ot", "metrics.json", "metrics.md", "semantic.png", "uncertainty.png",
                        "error.png", "quality.png"}) {
    EXPECT_TRUE(fs::exists(out_ + "/map/" + f)) << f;
    EXPECT_GT(fs::file_size(out_ + "/map/" + f), 100u) << f;
  }
}

TEST_F(CliEndToEnd, MetricsJsonIsLabelledAndInRange) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  const auto j = readJson(out_ + "/map/metrics.json");
  EXPECT_EQ(j["evidence_source"], "onehot");
  EXPECT_EQ(j["evidence_derived_from_hard_labels"], true);
  EXPECT_EQ(j["protocol"], "reconstruction");
  EXPECT_EQ(j["parameters"]["rule"], "dempster");
  EXPECT_EQ(j["parameters"]["drop_percent"], 10.0);
  EXPECT_EQ(j["map_scans"].size(), 2u);
  for (const char* k : {"semantic_coverage", "occupancy_coverage", "miou_all_queries",
                        "acc_all_queries", "miou_labelled", "ece"}) {
    const double v = j["map"][k];
    EXPECT_GE(v, 0.0) << k;
    EXPECT_LE(v, 1.0) << k;
  }
  EXPECT_GE(double(j["map"]["brier"]), 0.0);
  EXPECT_LE(double(j["map"]["brier"]), 2.0);
  for (const char* row : {"map", "input"}) {
    for (const char* output : {"u", "conflict", "1-max_p", "dissonance",
                               "error_probability"}) {
      EXPECT_TRUE(j[row]["error_detection"].contains(output)) << row << " " << output;
    }
    EXPECT_EQ(j[row]["queries"], j["map"]["queries"]) << "the same queries for every row";
  }
  EXPECT_GT(double(j["map"]["miou_all_queries"]), 0.2);
  EXPECT_EQ(j["map"]["occupied_without_endpoint"], 0) << "no kernel-made occupied voxels";
  const std::string md = map_result_.output;
  EXPECT_NE(md.find("derived from hard labels"), std::string::npos);
  EXPECT_NE(md.find("reconstruction"), std::string::npos);
}

TEST_F(CliEndToEnd, MetricsEqualAnIndependentComputation) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(out_ + "/map/map.ot"));
  auto* tree = dynamic_cast<EvidentialOcTree*>(any.get());
  ASSERT_NE(tree, nullptr);
  const ClassTable classes = ClassTable::load(kittiClasses());
  const Independent ind = recompute(*tree, classes);
  const auto j = readJson(out_ + "/map/metrics.json");
  EXPECT_EQ(size_t(j["map"]["queries"]), ind.queries);
  EXPECT_EQ(size_t(j["map"]["labelled"]), ind.labelled);
  EXPECT_EQ(size_t(j["map"]["occupied"]), ind.occupied);
  EXPECT_NEAR(double(j["map"]["semantic_coverage"]), double(ind.labelled) / ind.queries, 1e-12);
  EXPECT_NEAR(double(j["map"]["acc_all_queries"]), double(ind.correct) / ind.queries, 1e-12);
  EXPECT_NEAR(double(j["map"]["miou_all_queries"]), ind.miou_all, 1e-12);
  EXPECT_NEAR(double(j["map"]["brier"]), ind.brier, 1e-6);
  EXPECT_EQ(j["confusion"]["map"].get<std::vector<std::vector<size_t>>>(), ind.confusion);
  // The read-out cap the metrics were computed with: the adaptive cap of the saved map's m.
  const double m = tree->meanPointLogEvidence();
  EXPECT_GT(m, 0.0);
  EXPECT_DOUBLE_EQ(double(j["tree"]["mean_point_log_evidence"]), m);
  EXPECT_DOUBLE_EQ(double(j["tree"]["evidence_cap"]),
                   evidential_octomap::SemanticConfig::adaptiveEvidenceCap(m));
}

TEST_F(CliEndToEnd, InfoReadsTheMapBack) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  const Result r = run("info " + out_ + "/map/map.ot");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("EvidentialOcTree"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("classes (C):     20"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dempster"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("traffic-sign"), std::string::npos) << r.output;
  const auto j = readJson(out_ + "/map/metrics.json");
  const std::string sem = "semantic nodes:  " + std::to_string(size_t(j["tree"]["semantic_nodes"]));
  EXPECT_NE(r.output.find(sem), std::string::npos) << r.output;
}

TEST_F(CliEndToEnd, EvalOfTheSavedMapReproducesTheMetrics) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  const Result r = run("eval --map " + out_ + "/map/map.ot --data " + kittiDir() + " --classes " +
                       kittiClasses() + " --scans 2 --out " + out_ + "/eval");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto a = readJson(out_ + "/map/metrics.json"), b = readJson(out_ + "/eval/metrics.json");
  for (const char* k : {"queries", "labelled", "occupied", "semantic_coverage", "miou_all_queries",
                        "acc_all_queries", "brier", "nll", "ece", "error_detection"}) {
    EXPECT_EQ(a["map"][k], b["map"][k]) << k;
  }
  EXPECT_EQ(a["input"], b["input"]);
}

// eval --evidence-cap reads the stored evidence with another cap: the Brier score is the
// independent recomputation's at that cap; labels, coverage and accuracy do not move.
TEST_F(CliEndToEnd, EvalWithAnotherEvidenceCapChangesOnlyTheReadOut) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  const Result r =
      run("eval --map " + out_ + "/map/map.ot --data " + kittiDir() + " --classes " +
          kittiClasses() + " --scans 2 --evidence-cap 0 --out " + out_ + "/eval_nocap");
  ASSERT_EQ(r.status, 0) << r.output;
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(out_ + "/map/map.ot"));
  auto* tree = dynamic_cast<EvidentialOcTree*>(any.get());
  ASSERT_NE(tree, nullptr);
  evidential_octomap::SemanticConfig uncapped = tree->config();
  uncapped.evidence_cap = 0.0;
  tree->setConfig(uncapped);
  const Independent ind = recompute(*tree, ClassTable::load(kittiClasses()));
  const auto a = readJson(out_ + "/map/metrics.json"),
             b = readJson(out_ + "/eval_nocap/metrics.json");
  EXPECT_NEAR(double(b["map"]["brier"]), ind.brier, 1e-6);
  EXPECT_GT(std::fabs(double(a["map"]["brier"]) - double(b["map"]["brier"])), 1e-4);
  for (const char* k : {"labelled", "semantic_coverage", "acc_all_queries", "miou_all_queries"}) {
    EXPECT_EQ(a["map"][k], b["map"][k]) << k;
  }
  EXPECT_EQ(double(b["tree"]["evidence_cap"]), 0.0);
}

TEST_F(CliEndToEnd, ExportAndMergeWriteReadableMaps) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  const std::string map = out_ + "/map/map.ot";
  Result r = run("export --map " + map + " --classes " + kittiClasses() + " --color-octree " +
                 out_ + "/color.ot --mode uncertainty");
  ASSERT_EQ(r.status, 0) << r.output;
  std::unique_ptr<octomap::AbstractOcTree> color(octomap::AbstractOcTree::read(out_ + "/color.ot"));
  ASSERT_NE(dynamic_cast<octomap::ColorOcTree*>(color.get()), nullptr);
  r = run("merge " + map + " " + map + " -o " + out_ + "/merged.ot");
  ASSERT_EQ(r.status, 0) << r.output;
  r = run("info " + out_ + "/merged.ot");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("EvidentialOcTree"), std::string::npos);
}

// export --mode uncertainty colours the calibration's error probability: a model that gives
// every labelled voxel the same P(wrong) (an intercept alone) paints them all one colour.
TEST_F(CliEndToEnd, ExportColoursTheCalibrationsErrorProbability) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  const std::string map = out_ + "/map/map.ot", file = out_ + "/constant_error.yaml";
  std::ofstream(file) << "calibration_version: 2\ncalibration_rule: dempster\nevidence_cap: -1\n"
                         "error_model_terms: [intercept]\nerror_model_weights: [1.5]\n";
  const auto colours = [&](const std::string& extra, const std::string& out) {
    const Result r = run("export --map " + map + " --color-octree " + out +
                         " --mode uncertainty" + extra);
    EXPECT_EQ(r.status, 0) << r.output;
    std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(out));
    auto* color = dynamic_cast<octomap::ColorOcTree*>(read.get());
    std::set<std::array<uint8_t, 3>> seen;
    if (color == nullptr) return seen;
    for (auto it = color->begin_leafs(); it != color->end_leafs(); ++it) {
      const octomap::ColorOcTreeNode::Color c = it->getColor();
      if (c.r != 128 || c.g != 128 || c.b != 128) seen.insert({c.r, c.g, c.b});  // grey: none
    }
    return seen;
  };
  EXPECT_GT(colours("", out_ + "/plain_error.ot").size(), 10u);
  EXPECT_EQ(colours(" --calibration " + file, out_ + "/calibrated_error.ot").size(), 1u);
}

// kill -9 during `export --color-octree` (before the fix 41 of 50 kills destroyed the previous
// file when the export wrote it in place). The previous export must stay whole.
TEST_F(CliEndToEnd, ExportKilledAtAnyMomentLeavesTheOldFileWhole) {
  ASSERT_EQ(map_result_.status, 0) << map_result_.output;
  const std::string color = out_ + "/killed_color.ot";
  const std::string args_map = out_ + "/map/map.ot";
  const std::string classes = kittiClasses();
  auto exportArgs = [&] {
    return std::vector<std::string>{EVIDENTIAL_TEST_CLI, "export", "--map",          args_map,
                                    "--classes",         classes,  "--color-octree", color};
  };
  const auto t0 = std::chrono::steady_clock::now();
  Result first =
      run("export --map " + args_map + " --classes " + classes + " --color-octree " + color);
  ASSERT_EQ(first.status, 0) << first.output;
  const double export_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::ifstream in(color, std::ios::binary);
  const std::string before((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::mt19937 rng(16);
  std::uniform_real_distribution<double> delay(0.0, 1.2 * export_ms);
  for (int trial = 0; trial < 8; ++trial) {
    ASSERT_TRUE(killedAfter(delay(rng), [&] {
      std::vector<std::string> args = exportArgs();
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(&a[0]);
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
    }));
    std::ifstream after_in(color, std::ios::binary);
    const std::string after((std::istreambuf_iterator<char>(after_in)),
                            std::istreambuf_iterator<char>());
    ASSERT_TRUE(after == before) << "trial " << trial << ": the ColorOcTree file is torn ("
                                 << after.size() << " of " << before.size() << " B)";
  }
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(color));
  EXPECT_NE(dynamic_cast<octomap::ColorOcTree*>(read.get()), nullptr);
}

// --autosave-every N: every N scans the map so far is saved (atomically) beside the outputs;
// after 3 scans with N = 2 the autosave is the map of the first 2 scans. Derived evidence is
// rescaled to the error rate of the scans mapped, so both runs take it as is.
TEST_F(CliEndToEnd, MapAutosaveEveryNScansHoldsTheMapOfThoseScans) {
  const std::string out = out_ + "/autosave", two = out_ + "/autosave_two";
  const std::string map = "map --data " + kittiDir() + " --classes " + kittiClasses() +
                          " --quiet --no-render --no-calibration";
  const Result r = run(map + " --scans 3 --autosave-every 2 --out " + out);
  ASSERT_EQ(r.status, 0) << r.output;
  const Result r2 = run(map + " --scans 2 --out " + two);
  ASSERT_EQ(r2.status, 0) << r2.output;
  const auto autosave = evidential_octomap::loadMap(out + "/map.autosave.ot");
  const auto two_scans = evidential_octomap::loadMap(two + "/map.ot");
  const auto three_scans = evidential_octomap::loadMap(out + "/map.ot");
  EXPECT_EQ(autosave->getNumLeafNodes(), two_scans->getNumLeafNodes());
  EXPECT_EQ(autosave->numSemanticNodes(), two_scans->numSemanticNodes());
  EXPECT_NE(autosave->getNumLeafNodes(), three_scans->getNumLeafNodes());
  for (const auto& e : fs::directory_iterator(out)) {
    EXPECT_EQ(e.path().filename().string().find(".evidential-tmp."), std::string::npos) << e.path();
  }
}

TEST(CliErrors, MissingDataDirectoryFails) {
  const Result r = run("map --data /nonexistent/dir --classes " + kittiClasses());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("/nonexistent/dir"), std::string::npos) << r.output;
}

TEST(CliErrors, BadLabelFileIsNamed) {
  const std::string dir = freshDir("cli_bad_labels");
  fs::create_directories(dir + "/velodyne");
  fs::create_directories(dir + "/labels");
  fs::create_directories(dir + "/predictions");
  writeBinary(dir + "/velodyne/000000.bin", std::vector<float>(40, 1.0f));
  writeBinary(dir + "/labels/000000.label", std::vector<uint32_t>(10, 40));
  writeBinary(dir + "/predictions/000000.label", std::vector<uint32_t>(10, 12345));
  fs::copy_file(kittiDir() + "/calib.txt", dir + "/calib.txt");
  std::ofstream(dir + "/poses.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const Result r =
      run("map --quiet --data " + dir + " --classes " + kittiClasses() + " --out " + dir + "/out");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("predictions/000000.label"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("12345"), std::string::npos) << r.output;
}

TEST(CliErrors, EverySubcommandHasHelp) {
  for (const char* c : {"map", "eval", "compare", "export", "merge", "info"}) {
    const Result r = run(std::string(c) + " --help");
    EXPECT_EQ(r.status, 0) << c;
    EXPECT_NE(r.output.find("Usage:"), std::string::npos) << c;
  }
}

// A compare variant with overrides is an ablation row whose config holds the overrides;
// an unknown field is refused before anything runs.
TEST(CliCompare, VariantOverridesMakeAnAblationRow) {
  const std::string dir = freshDir("cli_compare_variant");
  const Result bad = run("compare --data " + kittiDir() + " --classes " + kittiClasses() +
                         " --variants dempster:no_such_field=1 --out " + dir);
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find("no_such_field"), std::string::npos) << bad.output;
  const Result r =
      run("compare -q --no-rellis --scans 1 --sources onehot --protocols "
          "reconstruction --variants dempster:drop_percent=0:evidence_cap=2 --data " +
          kittiDir() + " --classes " + kittiClasses() + " --out " + dir);
  ASSERT_EQ(r.status, 0) << r.output;
  const auto runs = readJson(dir + "/compare.json")["runs"];
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0]["variant_id"], "dempster:drop_percent=0:evidence_cap=2");
  EXPECT_EQ(double(runs[0]["parameters"]["drop_percent"]), 0.0);
  EXPECT_EQ(double(runs[0]["parameters"]["evidence_cap"]), 2.0);
}

// compare's paired bootstrap: one entry per row against default dempster, whose estimate is
// the difference of the two runs' own metrics (independently computed by the map metrics), inside
// its interval; the voxel-majority reference rows are among them.
TEST(CliCompare, BootstrapEntriesMatchTheRunsDifferences) {
  const std::string dir = freshDir("cli_compare_bootstrap");
  const Result r =
      run("compare -q --no-rellis --scans 1 --sources onehot --protocols "
          "reconstruction --variants dempster,ebs --bootstrap-replicates 200 --data " +
          kittiDir() + " --classes " + kittiClasses() + " --out " + dir);
  ASSERT_EQ(r.status, 0) << r.output;
  const auto all = readJson(dir + "/compare.json");
  const auto& runs = all["runs"];
  ASSERT_EQ(runs.size(), 2u);
  const auto metric = [&](const std::string& variant, const char* key) {
    for (const auto& run : runs)
      if (run["variant_id"] == variant) return double(run["map"][key]);
    ADD_FAILURE() << variant;
    return 0.0;
  };
  bool ebs_seen = false, majority_seen = false;
  for (const auto& b : all["bootstrap"]) {
    EXPECT_EQ(b["reference"], "dempster");
    EXPECT_EQ(int(b["replicates"]), 200);
    for (const char* key : {"miou_all_difference", "brier_difference"}) {
      EXPECT_LE(double(b[key]["lower"]), double(b[key]["estimate"]) + 1e-12) << b.dump();
      EXPECT_GE(double(b[key]["upper"]), double(b[key]["estimate"]) - 1e-12) << b.dump();
    }
    majority_seen |= std::string(b["row"]).find("voxel majority") != std::string::npos;
    if (b["row"] != "ebs") continue;
    ebs_seen = true;
    EXPECT_NEAR(double(b["miou_all_difference"]["estimate"]),
                metric("ebs", "miou_all_queries") - metric("dempster", "miou_all_queries"), 1e-9);
    EXPECT_NEAR(double(b["brier_difference"]["estimate"]),
                metric("ebs", "brier") - metric("dempster", "brier"), 1e-6);
  }
  EXPECT_TRUE(ebs_seen);
  EXPECT_TRUE(majority_seen);
  EXPECT_NE(r.output.find("Paired bootstrap"), std::string::npos);  // compare.md, printed
}

TEST(CliRellis, WithoutPredictionsAsksForSyntheticOnes) {
  const Result r = run("map --quiet --data " + rellisDir() + " --classes " + rellisClasses() +
                       " --out " + freshDir("cli_rellis_none"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("--synthetic-predictions"), std::string::npos) << r.output;
}

TEST(CliRellis, SyntheticPredictionsAreLabelledInTheOutputs) {
  const std::string out = freshDir("cli_rellis");
  const Result r = run("map --quiet --no-render --synthetic-predictions --data " + rellisDir() +
                       " --classes " + rellisClasses() + " --out " + out);
  ASSERT_EQ(r.status, 0) << r.output;
  const auto j = readJson(out + "/metrics.json");
  EXPECT_NE(std::string(j["predictions"]).find("synthetic"), std::string::npos);
  EXPECT_EQ(j["class_table"], "rellis3d");
  EXPECT_EQ(size_t(j["map"]["queries"]), 62788u);  // 77,708 valid points minus 14,920 void
  const double input_acc = j["input"]["acc_all_queries"];
  EXPECT_GT(input_acc, 0.75);  // about 1 - point rate - region rate
  EXPECT_LT(input_acc, 0.95);
}

// Issue 16 item 11: ctest -j2 runs several of these processes at once; each must get its own
// output directory (the CliEndToEnd suite once shared one and a concurrent run deleted it).
TEST(TestIsolation, ConcurrentProcessesNeverShareOrDeleteAFreshDirectory) {
  const std::string mine = freshDir("isolation");
  std::ofstream(mine + "/marker") << "mine";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // another test process making "the same" directory
    const std::string theirs = freshDir("isolation");
    const bool shared = theirs == mine;
    std::error_code ec;
    fs::remove_all(theirs, ec);
    ::_exit(shared ? 1 : 0);  // no atexit handlers: they belong to the parent's copy
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "both processes got " << mine;
  EXPECT_TRUE(fs::exists(mine + "/marker")) << "another process deleted " << mine;
}
