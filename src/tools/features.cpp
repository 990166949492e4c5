// `evidential_octomap features`: dump the learned evidence head's per-point features
// (point_features.h) of every scan as .npy, with GT and predictions, for the training script
// docs/experiments/drivers/learned_evidence/train.py. One feature implementation: this one.
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evidence/point_features.h"
#include "pipeline.h"
#include "report.h"

namespace evidential_octomap::tools {

namespace {

struct FeaturesOptions {
  std::string data, classes, out = "build/learned_features";
  size_t scans = 0;
  bool quiet = false;
};

std::vector<int32_t> asInt32(const std::vector<int>& v) { return {v.begin(), v.end()}; }

void runFeatures(const FeaturesOptions& o) {
  const ClassTable classes = ClassTable::load(o.classes);
  const Dataset dataset = Dataset::open(o.data, classes);
  if (!dataset.hasPredictions() || !dataset.hasLabels()) {
    throw std::runtime_error(o.data + ": features for training need labels/ and predictions/");
  }
  const std::vector<Scan> scans = loadScans(dataset, o.scans, !o.quiet);
  makeDirectories(o.out);
  const int C = classes.numClasses();
  nlohmann::json index;
  index["feature_names"] = pointFeatureNames(C);
  index["num_classes"] = C;
  index["class_names"] = classes.names;
  index["ignore_class"] = classes.ignore_class;
  index["dataset"] = o.data;
  index["scans"] = nlohmann::json::array();
  for (const Scan& scan : scans) {
    const ScanInput in = scanInput(scan);
    const FeatureMatrix f = computePointFeatures(in, C);
    const std::string stem = o.out + "/" + scan.name;
    writeNpy(stem + ".features.npy", f.values.data(), f.rows, size_t(f.cols));
    writeNpy(stem + ".gt.npy", asInt32(scan.gt).data(), scan.size(), 1);
    writeNpy(stem + ".pred.npy", asInt32(scan.predicted).data(), scan.size(), 1);
    index["scans"].push_back({{"name", scan.name},
                              {"points", scan.size()},
                              {"fingerprint", fingerprintHex(scanFingerprint(in))}});
    if (!o.quiet)
      std::cerr << "features: scan " << scan.name << " (" << f.rows << " x " << f.cols << ")\n";
  }
  writeText(o.out + "/index.json", index.dump(2) + "\n");
  std::cout << "wrote " << scans.size() << " scans of " << pointFeatureNames(C).size()
            << " features to " << o.out << "/\n";
}

}  // namespace

void addFeaturesCommand(CLI::App& app) {
  auto o = std::make_shared<FeaturesOptions>();
  CLI::App* cmd = app.add_subcommand(
      "features",
      "Write the learned evidence head's per-point features of each scan (<stem>.features.npy, "
      "float32 N x F), its GT and predictions (<stem>.gt.npy, <stem>.pred.npy, int32 class ids) "
      "and index.json (feature names, scan fingerprints) for the training script");
  addDataOptions(cmd, &o->data, "SemanticKITTI-layout directory with labels/ and predictions/",
                 &o->classes);
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--scans", o->scans, "Use only the first N scans (0: all)")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "No progress bars");
  cmd->callback([o]() { runFeatures(*o); });
}

}  // namespace evidential_octomap::tools
