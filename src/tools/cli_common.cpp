#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "evidential_octomap/calibration_file.h"
#include "commands.h"
#include "evidential_octomap/settings.h"

namespace evidential_octomap::tools {

namespace {
std::string& storedCommandLine() {
  static std::string line;
  return line;
}
}  // namespace

void setCommandLine(int argc, char** argv) {
  std::string line = "evidential_octomap";
  for (int i = 1; i < argc; ++i) line += std::string(" ") + argv[i];
  storedCommandLine() = line;
}

const std::string& commandLine() { return storedCommandLine(); }

void addDataOptions(CLI::App* cmd, std::string* data, const std::string& data_help,
                    std::string* classes) {
  cmd->add_option("--data", *data, data_help)->required()->check(CLI::ExistingPath);
  cmd->add_option("--classes", *classes, "Class table YAML (config/classes_*.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
}

// One CLI option per setting of settings.h, named, typed and described there.
void addConfigOptions(CLI::App* cmd, SemanticConfig* c, double* resolution) {
  cmd->add_option("--resolution", *resolution, "Voxel size [m]")->capture_default_str();
  for (const Setting& s : settingList()) {
    std::visit(
        [&](auto member) {
          auto& value = c->*member;
          CLI::Option* option = nullptr;
          if constexpr (std::is_same_v<std::decay_t<decltype(value)>, bool>) {
            option = s.cli_flag ? cmd->add_flag(s.cliName(), value, s.help)
                                : cmd->add_option(s.cliName(), value, s.help);
          } else {
            option = cmd->add_option(s.cliName(), value, s.help);
          }
          if (!s.choices.empty()) option->check(CLI::IsMember(s.choices));
          option->capture_default_str();
        },
        s.field);
  }
}

void addCalibrationOption(CLI::App* cmd, std::shared_ptr<const Calibration>* calibration) {
  CLI::Option* option =
      cmd->add_option_function<std::string>(
             "--calibration",
             [calibration](const std::string& path) {
               *calibration = std::make_shared<const Calibration>(readCalibration(path));
             },
             "Read the read-out cap and the error model from a file written by `calibrate` "
             "(instead of --evidence-cap)")
          ->check(CLI::ExistingFile);
  if (CLI::Option* cap = cmd->get_option_no_throw("--evidence-cap")) option->excludes(cap);
}

void useCalibration(const std::shared_ptr<const Calibration>& calibration,
                    const ClassTable& classes, SemanticConfig* config) {
  if (!calibration) return;
  const std::string problem = calibration->problemWith(classes.names, config->rule);
  if (!problem.empty()) throw std::runtime_error(problem);
  config->evidence_cap = calibration->evidence_cap;
}

void warnIfUncalibrated(const EvidenceOptions& evidence, bool calibrated) {
  static bool warned = false;
  const bool network =
      evidence.source == EvidenceSource::kFile || evidence.source == EvidenceSource::kLearned;
  if (calibrated || !network || warned) return;
  warned = true;
  std::cerr << "note: " << kUncalibratedNote << " (map --calibration FILE)\n";
}

void addEvidenceOptions(CLI::App* cmd, EvidenceOptions* o, std::string* source_name) {
  cmd->add_option("--evidence", *source_name,
                  "Evidence source: file (evidence/ or alpha/ of the dataset), onehot, knn-vote, "
                  "confusion (these three are derived from hard labels), learned (a small "
                  "evidential model, cross-fitted: each scan from the fold not trained on it)")
      ->check(CLI::IsMember({"file", "onehot", "knn-vote", "confusion", "learned"}))
      ->capture_default_str();
  cmd->add_option("--logit-transform", o->logit_transform_name,
                  "How logits/ files become evidence: softmax (ordinary network; then as "
                  "probabilities), exp or softplus (EDL network)")
      ->check(CLI::IsMember({"softmax", "exp", "softplus"}))
      ->capture_default_str();
  cmd->add_option("--probability-evidence", o->conversion.probability_magnitude,
                  "E of the confidence-scaled evidence of probabilities/ (and softmax logits): "
                  "e_c = E p_c (C p_max - 1) / (C - 1)")
      ->capture_default_str();
  cmd->add_option("--learned-model", o->learned_model,
                  "Model file of --evidence learned (default: <class table dir>/learned/"
                  "<dataset>.model)");
  cmd->add_option("-E,--evidence-magnitude", o->magnitude,
                  "Evidence magnitude E of derived sources")
      ->capture_default_str();
  cmd->add_option("--knn-k", o->knn_k, "Neighbours voting in knn-vote")->capture_default_str();
  cmd->add_option("--knn-radius", o->knn_radius, "Neighbour radius of knn-vote [m]")
      ->capture_default_str();
  cmd->add_flag("!--no-calibration", o->calibrate,
                "Derived evidence as is: no rescaling of u to the error rate of such points "
                "on the mapping scans");
}

void finishEvidenceOptions(const std::string& source_name, const std::string& classes_path,
                           const ClassTable& classes, EvidenceOptions* o) {
  o->source = evidenceSourceFromName(source_name);
  o->conversion.logit_transform = logitTransformFromName(o->logit_transform_name);
  if (o->learned_model.empty()) o->learned_model = defaultLearnedModel(classes_path, classes);
}

std::vector<std::string> captionLines(const std::string& what, const std::string& variant,
                                      const std::string& evidence, const std::string& kind,
                                      const std::string& protocol,
                                      const std::string& predictions_note) {
  std::vector<std::string> lines;
  lines.push_back(what + " | " + variant + " | protocol: " + protocol);
  lines.push_back("evidence: " + evidence +
                  (kind == "network evidence" ? " (network evidence)" : ""));
  if (!predictions_note.empty()) lines.push_back("predictions: " + predictions_note);
  return lines;
}

std::string variantName(const SemanticConfig& c) {
  std::string v = c.rule;
  if (c.rule == "dempster") {
    if (c.reference_compat) v += " reference_compat (gamma=0, count cap)";
    if (c.adaptive_length && !c.reference_compat) v += " + adaptive length";
    if (c.uncertainty_threshold && !c.reference_compat) v += " + threshold";
    if (c.evidence_cap == 0.0) v += " w/o evidence cap";
    if (c.sigma0 != SemanticConfig().sigma0 && !c.reference_compat)
      v += " sigma0 " + std::to_string(c.sigma0).substr(0, 4);
    if (c.kernel_distance != SemanticConfig().kernel_distance)
      v += " kernel distance " + c.kernel_distance;
    if (c.vertical_support != SemanticConfig().vertical_support)
      v += " vertical support " + std::to_string(c.vertical_support).substr(0, 4);
    if (c.ground_vertical_support != SemanticConfig().ground_vertical_support)
      v += " ground support " + std::to_string(c.ground_vertical_support).substr(0, 4);
    if (c.downsampling != SemanticConfig().downsampling && !c.reference_compat)
      v += " " + c.downsampling;
    if (c.other_class_weight != SemanticConfig().other_class_weight)
      v += " other-class weight " + std::to_string(c.other_class_weight).substr(0, 4);
  }
  return v;
}

void makeDirectories(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create directory: " + ec.message());
}

}  // namespace evidential_octomap::tools
