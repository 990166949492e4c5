// The learned evidence head: C++ inference against the training script's own outputs
// (test/fixtures/learned_evidence_points.txt, written by
// docs/experiments/drivers/learned_evidence/train.py), model-file errors, and the cross-fitting
// rule (a scan never gets a fold that saw it).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "evidential_octomap/evidence/learned_evidence.h"

namespace evidential_octomap {
namespace {

const std::string kSource = EVIDENTIAL_OCTOMAP_SOURCE_DIR;

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("eo_learned_" + name)).string();
}

void writeFile(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(LearnedEvidence, CppInferenceMatchesTheTrainingScript) {
  const LearnedEvidenceModel model =
      LearnedEvidenceModel::load(kSource + "/config/learned/semantickitti.model");
  const int C = model.numClasses();
  const int F = int(pointFeatureNames(C).size());
  std::ifstream in(kSource + "/test/fixtures/learned_evidence_points.txt");
  ASSERT_TRUE(in) << "fixture missing";
  std::string line;
  int checked = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("fold ", 0) != 0) continue;
    std::istringstream s(line);
    std::string word, fold_name;
    s >> word >> fold_name >> word;  // fold <name> features
    FeatureMatrix x;
    x.rows = 1;
    x.cols = F;
    x.values.resize(size_t(F));
    for (float& v : x.values) s >> v;
    s >> word;  // evidence
    std::vector<double> expected(static_cast<size_t>(C));
    for (double& v : expected) s >> v;
    ASSERT_TRUE(s) << "malformed fixture line: " << line.substr(0, 60);
    const LearnedEvidenceModel::Fold* fold = nullptr;
    for (const auto& f : model.folds())
      if (f.name == fold_name) fold = &f;
    ASSERT_NE(fold, nullptr) << fold_name;
    const std::vector<float> e = fold->mlp.forward(x);
    for (int c = 0; c < C; ++c) {
      EXPECT_NEAR(e[size_t(c)], expected[size_t(c)], 1e-4 + 1e-4 * std::abs(expected[size_t(c)]))
          << "fold " << fold_name << " class " << c;
    }
    ++checked;
  }
  EXPECT_GE(checked, 8);
}

// A hand-written two-class model with two folds: every weight 0, so the evidence of class c is
// softplus(bias_c) = log(1 + exp(bias_c)) whatever the features.
std::string tinyModel(uint64_t trained_x, uint64_t trained_y) {
  const int C = 2;
  const auto names = pointFeatureNames(C);
  std::ostringstream s;
  s << "evidential_octomap_learned_evidence 1\nclasses 2\nfeatures " << names.size();
  for (const auto& n : names) s << ' ' << n;
  s << "\ndescription a test model\nfolds 2\n";
  const double biases[2][2] = {{1.0, -1.0}, {0.0, 2.0}};
  for (int f = 0; f < 2; ++f) {
    s << "fold " << (f == 0 ? "X" : "Y") << " trained_on 1 "
      << fingerprintHex(f == 0 ? trained_x : trained_y) << "\nnormalise";
    for (size_t k = 0; k < names.size(); ++k) s << " 0";
    for (size_t k = 0; k < names.size(); ++k) s << " 1";
    s << "\nlayers 1\ndense " << names.size() << " 2 softplus";
    for (size_t k = 0; k < 2 * names.size(); ++k) s << " 0";
    s << ' ' << biases[f][0] << ' ' << biases[f][1] << '\n';
  }
  s << "end\n";
  return s.str();
}

struct TwoScans {
  std::vector<float> xyz1{5, 0, -1, 5.1f, 0, -1}, xyz2{7, 1, -1, 7.1f, 1, -1};
  std::vector<int> pred{0, 1};
  ScanInput scan1() const { return {xyz1.data(), nullptr, pred.data(), 2}; }
  ScanInput scan2() const { return {xyz2.data(), nullptr, pred.data(), 2}; }
};

TEST(LearnedEvidence, EachScanGetsOnlyTheFoldsThatDidNotSeeIt) {
  TwoScans t;
  const uint64_t id1 = scanFingerprint(t.scan1()), id2 = scanFingerprint(t.scan2());
  const std::string path = tempPath("folds.model");
  writeFile(path, tinyModel(id1, id2));  // fold X saw scan 1, fold Y saw scan 2
  const LearnedEvidenceModel m = LearnedEvidenceModel::load(path);
  std::vector<size_t> used;
  const std::vector<float> e1 = m.evidence(t.scan1(), &used);
  ASSERT_EQ(used, std::vector<size_t>{1});  // Y only
  EXPECT_NEAR(e1[0], std::log(2.0), 1e-6);
  EXPECT_NEAR(e1[1], std::log(1.0 + std::exp(2.0)), 1e-6);
  const std::vector<float> e2 = m.evidence(t.scan2(), &used);
  ASSERT_EQ(used, std::vector<size_t>{0});  // X only
  EXPECT_NEAR(e2[2], std::log(1.0 + std::exp(1.0)), 1e-6);
  EXPECT_NEAR(e2[3], std::log(1.0 + std::exp(-1.0)), 1e-6);
}

TEST(LearnedEvidence, UnseenScansAverageEveryFold) {
  TwoScans t;
  const std::string path = tempPath("unseen.model");
  writeFile(path, tinyModel(1, 2));
  const std::vector<float> e = LearnedEvidenceModel::load(path).evidence(t.scan1());
  EXPECT_NEAR(e[0], 0.5 * (std::log(1.0 + std::exp(1.0)) + std::log(2.0)), 1e-6);
}

TEST(LearnedEvidence, AScanEveryFoldSawIsRefused) {
  TwoScans t;
  const uint64_t id1 = scanFingerprint(t.scan1());
  const std::string path = tempPath("seen.model");
  writeFile(path, tinyModel(id1, id1));
  EXPECT_THROW(LearnedEvidenceModel::load(path).evidence(t.scan1()), std::runtime_error);
}

TEST(LearnedEvidence, BadModelFilesNameTheFileAndTheProblem) {
  auto message = [](const std::string& text) {
    const std::string path = tempPath("bad.model");
    writeFile(path, text);
    try {
      LearnedEvidenceModel::load(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string good = tinyModel(1, 2);
  EXPECT_NE(message("hello").find("not a learned-evidence model"), std::string::npos);
  EXPECT_NE(message(good.substr(0, good.size() / 2)).find("truncated"), std::string::npos);
  std::string renamed = good;
  renamed.replace(renamed.find("range"), 5, "rangE");
  EXPECT_NE(message(renamed).find("not this build's point features"), std::string::npos);
  std::string relu = good;
  relu.replace(relu.find("softplus"), 8, "relu");
  EXPECT_NE(message(relu).find("softplus"), std::string::npos);
  EXPECT_NE(message(good).find("no error"), std::string::npos);
  EXPECT_THROW(LearnedEvidenceModel::load(tempPath("does_not_exist")), std::runtime_error);
}

}  // namespace
}  // namespace evidential_octomap
