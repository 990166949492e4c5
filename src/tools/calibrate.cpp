// `evidential_octomap calibrate`: fit the network-evidence calibration (scale and power, see
// evidential_octomap/input_calibration.h) on labelled scans of a user's own (a validation split),
// or without labels on cross-scan agreement, and write it as a small YAML file that `map`,
// `compare`, the node (~calibration) and Python (InputCalibration.load) read.
#include <iomanip>
#include <iostream>
#include <memory>

#include "calibration_fit.h"
#include "commands.h"
#include "consensus_labels.h"
#include "dataset.h"
#include "pipeline.h"

namespace evidential_octomap::tools {

namespace {

struct CalibrateOptions {
  std::string data, classes, out = "calibration.yaml";
  std::string labels = "gt";
  size_t scans = 0;
  double resolution = 0.2;
  InputConversion conversion;
  std::string logit_transform_name = "softmax";
};

void runCalibrate(const CalibrateOptions& o) {
  const ClassTable classes = ClassTable::load(o.classes);
  InputConversion conversion = o.conversion;
  conversion.logit_transform = logitTransformFromName(o.logit_transform_name);
  const Dataset dataset = Dataset::open(o.data, classes, conversion);
  if (!dataset.hasEvidence()) {
    throw std::runtime_error(o.data + ": no evidence/, alpha/, logits/ or probabilities/ files: "
                             "calibrate fits a network's outputs");
  }
  if (o.labels == "gt" && !dataset.hasLabels()) {
    throw std::runtime_error(o.data + ": no labels/ to calibrate on; use --labels consensus "
                             "(no labels needed)");
  }
  const std::vector<Scan> scans = loadScans(dataset, o.scans, true);
  std::vector<size_t> all(scans.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  std::vector<std::vector<float>> evidence(scans.size());
  std::vector<std::vector<int>> labels(scans.size());
  for (size_t s : all) {
    evidence[s] = scans[s].evidence;
    if (o.labels == "gt") labels[s] = scans[s].gt;
  }
  if (o.labels == "consensus") {
    labels = consensusLabels(scans, all, evidence, classes.numClasses(), o.resolution);
  }
  CalibrationFit fit =
      fitInputCalibration(evidence, labels, classes.numClasses(), classes.ignore_class);
  fit.calibration.labels = o.labels;
  fit.calibration.fitted_on = o.data + " (" + std::to_string(scans.size()) + " scans, " +
                              dataset.describeEvidenceFiles() + ")";
  fit.calibration.save(o.out);
  std::cout << std::setprecision(4) << "calibration: " << fit.calibration.describe() << "\n"
            << "  fitted on " << fit.points << " points against "
            << (o.labels == "gt" ? "GT labels" : "cross-scan consensus") << "; mean NLL "
            << fit.nll_before << " -> " << fit.nll_after << "\nwrote " << o.out << "\n";
}

}  // namespace

void addCalibrateCommand(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate",
      "Fit the calibration of a network's evidence (e' = scale * e^power) on labelled scans "
      "(a validation split of your own) or without labels, and write it for map, compare, the "
      "node (~calibration) and Python");
  addDataOptions(cmd, &o->data, "Dataset directory with evidence/ (or logits/, probabilities/)",
                 &o->classes);
  cmd->add_option("--out", o->out, "Calibration file to write")->capture_default_str();
  cmd->add_option("--labels", o->labels,
                  "gt (the dataset's labels/) or consensus (no labels: each point against the "
                  "other scans' predictions of its voxel)")
      ->check(CLI::IsMember({"gt", "consensus"}))
      ->capture_default_str();
  cmd->add_option("--scans", o->scans, "Use only the first N scans (0: all)")
      ->capture_default_str();
  cmd->add_option("--resolution", o->resolution, "Voxel size of the consensus [m]")
      ->capture_default_str();
  cmd->add_option("--logit-transform", o->logit_transform_name,
                  "How logits/ files become evidence: softmax, exp or softplus")
      ->check(CLI::IsMember({"softmax", "exp", "softplus"}))
      ->capture_default_str();
  cmd->callback([o]() { runCalibrate(*o); });
}

}  // namespace evidential_octomap::tools
