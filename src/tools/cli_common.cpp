#include <filesystem>
#include <stdexcept>

#include "calibration_file.h"
#include "commands.h"

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

void addConfigOptions(CLI::App* cmd, SemanticConfig* c, double* resolution) {
  cmd->add_option("--resolution", *resolution, "Voxel size [m]")->capture_default_str();
  cmd->add_option("--rule", c->rule, "Fusion rule: dempster, sbki or ebs")
      ->check(CLI::IsMember({"dempster", "sbki", "ebs"}))
      ->capture_default_str();
  cmd->add_option("--length-scale", c->length_scale, "Kernel length scale l [m]")
      ->capture_default_str();
  cmd->add_option("--sigma0", c->sigma0, "Kernel amplitude")->capture_default_str();
  cmd->add_option("--beta", c->beta, "Adaptive length factor beta")->capture_default_str();
  cmd->add_option("--gamma", c->gamma, "Adaptive length decay gamma")->capture_default_str();
  cmd->add_option("--drop-percent", c->drop_percent,
                  "Percentage psi of the most uncertain points dropped per scan")
      ->capture_default_str();
  cmd->add_flag("--adaptive-length,!--no-adaptive-length", c->adaptive_length,
                "The paper's adaptive support l*beta*e^(1-gamma u) (default off: gamma = 0, "
                "support l*beta*e; Table II ablation)")
      ->capture_default_str();
  cmd->add_flag("--threshold,!--no-threshold", c->uncertainty_threshold,
                "The paper's percentile threshold: drop the --drop-percent most uncertain "
                "points of each scan (default off; Table II ablation)")
      ->capture_default_str();
  cmd->add_flag("--reference-compat", c->reference_compat,
                "The authors' released configuration: gamma = 0 (support l*beta*e), count-cap "
                "down-sampling and the percentile threshold");
  cmd->add_option("--sbki-prior", c->sbki_prior, "S-BKI prior alpha0")->capture_default_str();
  cmd->add_option("--evidence-cap", c->evidence_cap,
                  "dempster: read opinions with the fused log-evidence capped here: -1 follows "
                  "the evidence (docs/calibration.md), 0 no cap, > 0 a fixed cap (e.g. from "
                  "'calibrate')")
      ->capture_default_str();
  cmd->add_option("--downsampling", c->downsampling,
                  "Semantic input down-sampling: average (grid of resolution/ds_multiplier) or "
                  "count_cap (the authors': at most ds_multiplier+1 points per 2x2x2-voxel block)")
      ->check(CLI::IsMember({"average", "count_cap"}))
      ->capture_default_str();
  cmd->add_option("--ds-multiplier", c->ds_multiplier,
                  "Down-sampling parameter (see --downsampling; <= 0: off)")
      ->capture_default_str();
  cmd->add_option("--kernel-distance", c->kernel_distance,
                  "Point-to-voxel distance of the kernel: voxel (to the voxel's cube, so a point "
                  "always reaches its own voxel) or centre")
      ->check(CLI::IsMember({"voxel", "centre"}))
      ->capture_default_str();
  cmd->add_option("--max-range", c->max_range, "Max sensor range [m] (< 0: unlimited)")
      ->capture_default_str();
  cmd->add_option("--kernel-creates-leaves", c->kernel_creates_leaves,
                  "Kernel updates may create leaves in unknown space (true/false)")
      ->capture_default_str();
  cmd->add_option("--threads", c->threads, "Threads of the semantic pass (0: OpenMP default)")
      ->capture_default_str();
  cmd->add_option("--fast-free-space", c->fast_free_space,
                  "Fast free space for live use: rays stop in space this scan already cleared "
                  "(not exact; true/false)")
      ->capture_default_str();
  cmd->add_option("--semantic-occupied-only", c->semantic_occupied_only,
                  "Semantic evidence only for occupied voxels and this scan's end voxels, for "
                  "live use: about 4x less kernel work (not exact; true/false)")
      ->capture_default_str();
  cmd->add_option("--evidence-floor", c->evidence_floor,
                  "Point evidence below this counts as 0 (0: off; 0.01 makes learned evidence "
                  "about as cheap as one-hot)")
      ->capture_default_str();
}

void addCalibrationOption(CLI::App* cmd, double* evidence_cap) {
  CLI::Option* calibration =
      cmd->add_option_function<std::string>(
             "--calibration",
             [evidence_cap](const std::string& path) { *evidence_cap = readCalibrationCap(path); },
             "Read the dempster read-out cap from a file written by `calibrate` (instead of "
             "--evidence-cap)")
          ->check(CLI::ExistingFile);
  if (CLI::Option* cap = cmd->get_option_no_throw("--evidence-cap")) calibration->excludes(cap);
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
    if (c.kernel_distance != SemanticConfig().kernel_distance)
      v += " kernel distance " + c.kernel_distance;
    if (c.downsampling != SemanticConfig().downsampling && !c.reference_compat)
      v += " " + c.downsampling;
  }
  return v;
}

void makeDirectories(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create directory: " + ec.message());
}

}  // namespace evidential_octomap::tools
