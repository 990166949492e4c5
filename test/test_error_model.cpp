// The error model (error_model.h) and the calibration file that carries it
// (calibration_file.h): the fit recovers a known error law, a file written is read back to the
// same model, and files that do not fit the map are refused with what differs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "evidential_octomap/calibration_file.h"
#include "evidential_octomap/error_model.h"
#include "evidential_octomap/evidential_octree.h"

using namespace evidential_octomap;

namespace {

std::string tempFile(const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(path) << text;
  return path;
}

// Rows whose error law is known: P(wrong) = sigmoid(2 x0 - 3 x5 + 1) for label 0, one unit
// higher for label 1, and non-monotone in x1 (errors at both ends), which no single feature
// and no monotone read-out of one ranks.
std::vector<ErrorRow> knownLawRows(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform;
  std::vector<ErrorRow> rows(n);
  for (size_t i = 0; i < n; ++i) {
    ErrorRow& r = rows[i];
    for (double& v : r.x) v = normal(rng);
    r.label = int(i % 2);
    const double z = 2.0 * r.x[0] - 3.0 * r.x[5] + 1.5 * std::fabs(r.x[1]) - 1.0 + r.label;
    r.wrong = uniform(rng) < 1.0 / (1.0 + std::exp(-z));
    r.fold = uint32_t(i / 100);
  }
  return rows;
}

double rowAuroc(const std::vector<ErrorRow>& rows, const std::vector<double>& score) {
  double above = 0.0, pairs = 0.0;
  std::vector<double> wrong, right;
  for (size_t i = 0; i < rows.size(); ++i) (rows[i].wrong ? wrong : right).push_back(score[i]);
  std::sort(right.begin(), right.end());
  for (double w : wrong) {
    above += double(std::lower_bound(right.begin(), right.end(), w) - right.begin());
    pairs += double(right.size());
  }
  return above / pairs;
}

TEST(ErrorModel, TheFitRecoversAKnownLawAndBeatsEverySingleFeatureOnHeldOutFolds) {
  const std::vector<ErrorRow> rows = knownLawRows(20000, 1);
  const ErrorModelFitResult fit = fitErrorModel(rows, 2);
  const double model = rowAuroc(rows, fit.out_of_fold);
  for (int f = 0; f < ErrorModel::kNumFeatures; ++f) {
    std::vector<double> single(rows.size()), reversed(rows.size());
    for (size_t i = 0; i < rows.size(); ++i) single[i] = rows[i].x[f], reversed[i] = -rows[i].x[f];
    const double best = std::max(rowAuroc(rows, single), rowAuroc(rows, reversed));
    EXPECT_GT(model, best + 0.03) << ErrorModel::featureNames()[f];
  }
  // On fresh rows of the same law, the predicted probabilities are calibrated.
  const std::vector<ErrorRow> fresh = knownLawRows(20000, 2);
  double predicted = 0.0, observed = 0.0;
  for (const ErrorRow& r : fresh) {
    if (r.x[0] < 0.5) continue;  // one slice of the rows, not only the mean over all
    predicted += fit.model.probability(r.x, r.label);
    observed += r.wrong;
  }
  EXPECT_NEAR(predicted / observed, 1.0, 0.05);
}

// A confident network fuses hundreds of units of log-evidence into one class: e^(L) of the others
// underflows against it, and a feature must still be a finite number (a -inf poisons the fit).
TEST(ErrorModel, FeaturesOfExtremeEvidenceAreFinite) {
  const int C = 3;
  for (const std::array<float, 3>& payload :
       {std::array<float, 3>{1000.f, 0.f, 0.f}, {0.f, 0.f, 0.f}, {800.f, 799.f, 0.f}}) {
    VoxelOpinion o;
    o.label = 0;
    o.belief = {0.6f, 0.1f, 0.0f};
    o.uncertainty = 0.3f;
    const ErrorModel::Features x = ErrorModel::features(payload.data(), o, C);
    for (int f = 0; f < ErrorModel::kNumFeatures; ++f) {
      EXPECT_TRUE(std::isfinite(x[f])) << ErrorModel::featureNames()[f] << " of " << payload[0];
    }
  }
  // The label's Dirichlet variance p (1 - p) / (S + 1), alpha = e^L, written out.
  const std::array<float, 3> even{2.f, 1.f, 1.f};
  VoxelOpinion o;
  o.label = 0;
  o.belief = {0.5f, 0.2f, 0.2f};
  o.uncertainty = 0.1f;
  const double s = std::exp(2.0) + 2.0 * std::exp(1.0), p = std::exp(2.0) / s;
  EXPECT_NEAR(ErrorModel::features(even.data(), o, C)[4], std::log(p * (1 - p) / (s + 1)), 1e-9);
}

TEST(ErrorModel, RowsThatAreAllRightCannotBeFitted) {
  std::vector<ErrorRow> rows = knownLawRows(500, 3);
  for (ErrorRow& r : rows) r.wrong = false;
  EXPECT_THROW(fitErrorModel(rows, 2), std::runtime_error);
}

TEST(ErrorModel, TermsThatDoNotParseAreRefusedByName) {
  EXPECT_THROW(ErrorModel({"intercept", "loudness"}, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ErrorModel({"intercept", "vacuity>x"}, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ErrorModel({"intercept", "label=-1"}, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ErrorModel({"intercept"}, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ErrorModel({"intercept"}, {NAN}), std::invalid_argument);
}

Calibration fittedCalibration() {
  const ErrorModelFitResult fit = fitErrorModel(knownLawRows(4000, 4), 2);
  Calibration c;
  c.classes = {"road", "tall grass"};  // a name YAML must quote
  c.evidence_cap = 6.5;
  c.error_model = std::make_shared<const ErrorModel>(fit.model);
  return c;
}

TEST(CalibrationFile, AFileWrittenIsReadBackToTheSameModel) {
  const Calibration written = fittedCalibration();
  const std::string path = tempFile("em_round_trip.yaml", calibrationText(written, "a comment\nand two lines"));
  const Calibration read = readCalibration(path);
  EXPECT_EQ(read.version, Calibration::kVersion);
  EXPECT_EQ(read.rule, "dempster");
  EXPECT_EQ(read.classes, written.classes);
  EXPECT_EQ(read.evidence_cap, 6.5);
  ASSERT_TRUE(read.error_model);
  EXPECT_EQ(read.error_model->terms(), written.error_model->terms());
  for (const ErrorRow& r : knownLawRows(200, 5)) {
    EXPECT_NEAR(read.error_model->probability(r.x, r.label),
                written.error_model->probability(r.x, r.label), 1e-8);
  }
}

TEST(CalibrationFile, AVersionOneFileIsACapAlone) {
  const Calibration c = readCalibration(tempFile("em_v1.yaml", "# old\nevidence_cap: 4\n"));
  EXPECT_EQ(c.version, 1);
  EXPECT_EQ(c.evidence_cap, 4.0);
  EXPECT_FALSE(c.error_model);
  EXPECT_TRUE(c.classes.empty());
}

void expectRefused(const std::string& text, const std::string& message) {
  const std::string path = tempFile("em_bad.yaml", text);
  try {
    readCalibration(path);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

TEST(CalibrationFile, FilesThatDoNotParseAreRefusedWithWhatIsWrong) {
  expectRefused("calibration_version: 3\nevidence_cap: -1\n", "calibration_version 3 is not one");
  expectRefused("evidence_cap: -1\nerror_model_terms: [intercept, loudness]\n"
                "error_model_weights: [0, 1]\n",
                "unknown feature 'loudness'");
  expectRefused("evidence_cap: -1\nerror_model_terms: [intercept, vacuity]\n"
                "error_model_weights: [0]\n",
                "2 terms but 1 weights");
  expectRefused("evidence_cap: -1\nerror_model_weights: [0, x]\n", "'x' is not a number");
  expectRefused("evidence_cap: -1\ncalibration_classes: road, grass\n", "a list in brackets");
  expectRefused("evidence_cap: -1\nlength_scale: 2\n", "em_bad.yaml:2: unknown key 'length_scale'");
}

TEST(CalibrationFile, AMapOfOtherClassesOrAnotherRuleIsRefused) {
  const Calibration c = fittedCalibration();
  EvidentialOcTree three(0.2, 3);
  EXPECT_THROW(applyCalibration(c, &three), std::runtime_error);
  EvidentialOcTree tree(0.2, 2);
  tree.setClassNames({"road", "tall grass"});
  SemanticConfig sbki = tree.config();
  sbki.rule = "sbki";
  EvidentialOcTree sbki_tree(0.2, 2, sbki);
  sbki_tree.setClassNames({"road", "tall grass"});
  const std::string problem = c.problemWith(sbki_tree.classNames(), sbki_tree.rule().name());
  EXPECT_NE(problem.find("fitted for the dempster rule"), std::string::npos) << problem;
  EXPECT_THROW(applyCalibration(c, &sbki_tree), std::runtime_error);
  const std::string classes = c.problemWith({"road", "grass"}, "dempster");
  EXPECT_NE(classes.find("[road, tall grass]"), std::string::npos) << classes;
  EXPECT_NE(classes.find("[road, grass]"), std::string::npos) << classes;
  applyCalibration(c, &tree);
  EXPECT_EQ(tree.config().evidence_cap, 6.5);
  EXPECT_EQ(tree.errorModel(), c.error_model);
}

// A voxel's answer follows the model: errorProbability and the projected probabilities.
TEST(CalibrationFile, TheTreeAnswersTheModelsErrorProbability) {
  EvidentialOcTree tree(0.2, 2);
  tree.setClassNames({"road", "tall grass"});
  octomap::Pointcloud cloud;
  cloud.push_back(1.0f, 0.0f, 0.0f);
  tree.insertSemanticScan(cloud, {8.0f, 1.0f}, octomap::pose6d());
  const VoxelOpinion plain = tree.query(octomap::point3d(1.0f, 0.0f, 0.0f));
  ASSERT_EQ(plain.label, 0);
  EXPECT_LT(plain.error_probability, 0.0f);  // no model
  // A model that answers 0.3 whatever the voxel holds.
  const auto constant = std::make_shared<const ErrorModel>(std::vector<std::string>{"intercept"},
                                                           std::vector<double>{std::log(0.3 / 0.7)});
  tree.setErrorModel(constant);
  const VoxelOpinion modelled = tree.query(octomap::point3d(1.0f, 0.0f, 0.0f));
  EXPECT_NEAR(tree.rule().errorProbability(modelled), 0.3, 1e-6);
  const std::vector<float> p = tree.rule().probabilities(modelled);
  EXPECT_NEAR(p[0], 0.7, 1e-6);
  EXPECT_NEAR(p[0] + p[1], 1.0, 1e-6);
  // Kept when the settings change; removed with null.
  SemanticConfig config = tree.config();
  config.evidence_cap = 2.0;
  tree.setConfig(config);
  EXPECT_NEAR(tree.rule().errorProbability(tree.query(octomap::point3d(1.0f, 0.0f, 0.0f))), 0.3,
              1e-6);
  tree.setErrorModel(nullptr);
  EXPECT_LT(tree.query(octomap::point3d(1.0f, 0.0f, 0.0f)).error_probability, 0.0f);
}

}  // namespace
