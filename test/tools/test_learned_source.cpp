// --evidence learned on the bundled SemanticKITTI scans: each scan gets the committed model's
// fold that was not trained on it, and the C++ features + inference reproduce the accuracy the
// training script computed for that scan (test/fixtures/learned_evidence_points.txt).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evidence/evidence_sources.h"
#include "test_helpers.h"

using namespace evidential_octomap;

namespace {

std::string modelPath() {
  return std::string(EVIDENTIAL_TEST_CONFIG_DIR) + "/learned/semantickitti.model";
}

// "scan <stem> fold <name> accuracy <value>" lines of the fixture.
double scriptAccuracy(const std::string& stem, std::string* fold) {
  std::ifstream in(std::string(EVIDENTIAL_TEST_CONFIG_DIR) +
                   "/../test/fixtures/learned_evidence_points.txt");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string word, name, f;
    double acc = -1;
    s >> word >> name;
    if (word != "scan" || name != stem) continue;
    s >> word >> f >> word >> acc;
    *fold = f;
    return acc;
  }
  ADD_FAILURE() << "no accuracy of scan " << stem << " in the fixture";
  return -1;
}

TEST(LearnedSource, BundledScansGetTheFoldThatDidNotSeeThem) {
  const ClassTable classes = ClassTable::load(tools_test::kittiClasses());
  EXPECT_EQ(defaultLearnedModel(tools_test::kittiClasses(), classes), modelPath());
  const LearnedEvidenceModel model = LearnedEvidenceModel::load(modelPath());
  const Dataset d = Dataset::open(tools_test::kittiDir(), classes);
  for (size_t s : {size_t(0), size_t(5)}) {
    const Scan scan = d.load(s);
    const auto folds = model.heldOutFolds(scanFingerprint(scanInput(scan)));
    ASSERT_EQ(folds.size(), 1u) << "scan " << scan.name;
    EXPECT_EQ(model.folds()[folds[0]].name, s < 5 ? "B" : "A") << "scan " << scan.name;
  }
}

TEST(LearnedSource, CppEvidenceReproducesTheScriptsAccuracyOnScan0) {
  const ClassTable classes = ClassTable::load(tools_test::kittiClasses());
  const Scan scan = Dataset::open(tools_test::kittiDir(), classes).load(0);
  EvidenceOptions o;
  o.source = EvidenceSource::kLearned;
  o.learned_model = modelPath();
  const LearnedEvidenceModel model = LearnedEvidenceModel::load(modelPath());
  const int C = classes.numClasses();
  const std::vector<float> e = deriveEvidence(scan, 0, o, C, nullptr, &model);
  ASSERT_EQ(e.size(), scan.size() * size_t(C));
  size_t n = 0, correct = 0;
  for (size_t i = 0; i < scan.size(); ++i) {
    for (int c = 0; c < C; ++c) ASSERT_GE(e[i * C + c], 0.0f);
    if (scan.gt[i] == classes.ignore_class) continue;
    const float* row = e.data() + i * C;
    ++n;
    correct += int(std::max_element(row, row + C) - row) == scan.gt[i];
  }
  std::string fold;
  const double expected = scriptAccuracy("000000", &fold);
  EXPECT_EQ(fold, "B");
  EXPECT_NEAR(double(correct) / double(n), expected, 1e-3);
  EXPECT_EQ(evidenceKind(EvidenceSource::kLearned), "learned (cross-fitted)");
  EXPECT_FALSE(derivedFromHardLabels(EvidenceSource::kLearned));
  EXPECT_NE(describeEvidence(o).find("cross-fitted"), std::string::npos);
}

TEST(LearnedSource, ScansWithoutPredictionsAreRefused) {
  const ClassTable classes = ClassTable::load(tools_test::kittiClasses());
  Scan scan = Dataset::open(tools_test::kittiDir(), classes).load(0);
  scan.predicted.clear();
  EvidenceOptions o;
  o.source = EvidenceSource::kLearned;
  const LearnedEvidenceModel model = LearnedEvidenceModel::load(modelPath());
  EXPECT_THROW(deriveEvidence(scan, 0, o, classes.numClasses(), nullptr, &model),
               std::runtime_error);
}

}  // namespace

// The CLI end to end: `features` for the training script, `map --evidence learned` labelled.
namespace {

int runCli(const std::string& args) {
  return std::system((std::string(EVIDENTIAL_TEST_CLI) + " " + args + " > /dev/null 2>&1").c_str());
}

TEST(LearnedSourceCli, FeaturesWritesNpyAndIndex) {
  const std::string out = tools_test::freshDir("learned_features");
  ASSERT_EQ(runCli("features --data " + tools_test::kittiDir() + " --classes " +
                   tools_test::kittiClasses() + " --scans 1 -q --out " + out),
            0);
  std::ifstream index(out + "/index.json");
  const std::string text((std::istreambuf_iterator<char>(index)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"height_above_ground\""), std::string::npos);
  const ClassTable classes = ClassTable::load(tools_test::kittiClasses());
  const Scan scan = Dataset::open(tools_test::kittiDir(), classes).load(0);
  EXPECT_NE(text.find(fingerprintHex(scanFingerprint(scanInput(scan)))), std::string::npos);
  const size_t F = pointFeatureNames(classes.numClasses()).size();
  EXPECT_EQ(readFloatMatrix(out + "/000000.features.npy", scan.size(), F).size(), scan.size() * F);
}

TEST(LearnedSourceCli, MapWithLearnedEvidenceIsLabelledCrossFitted) {
  const std::string out = tools_test::freshDir("learned_map");
  ASSERT_EQ(
      runCli("map --data " + tools_test::kittiDir() + " --classes " + tools_test::kittiClasses() +
             " --evidence learned --scans 1 -q --no-render " + "--out " + out),
      0);
  std::ifstream in(out + "/metrics.json");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"evidence_kind\": \"learned (cross-fitted)\""), std::string::npos);
  EXPECT_NE(text.find("\"evidence_derived_from_hard_labels\": false"), std::string::npos);
  EXPECT_EQ(text.find("(derived from hard labels)"), std::string::npos);
}

TEST(LearnedSourceCli, MissingModelIsAClearError) {
  const std::string out = tools_test::freshDir("learned_missing");
  EXPECT_NE(runCli("map --data " + tools_test::kittiDir() + " --classes " +
                   tools_test::kittiClasses() + " --evidence learned --learned-model " + out +
                   "/none.model --scans 1 -q --no-render --out " + out),
            0);
}

}  // namespace
