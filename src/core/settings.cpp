#include "evidential_octomap/settings.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "evidential_octomap/fusion_rule.h"
#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr SettingScope kMap = SettingScope::kMap, kInsert = SettingScope::kInsert;

constexpr SettingRange kPositive{0.0, kInf, true, true, kNaN, "finite and > 0"};

// One entry of the list: name, field, scope and help, then what differs from the defaults.
struct Entry {
  Setting s{};
  template <class T, class Base>
  Entry(const char* name, T Base::*member, SettingScope scope, const char* help) {
    s.name = name;
    s.field = static_cast<T SemanticConfig::*>(member);
    s.scope = scope;
    s.help = help;
  }
  Entry&& range(const SettingRange& r) && {
    s.range = r;
    return std::move(*this);
  }
  Entry&& choices(std::vector<std::string> values) && {
    s.choices = std::move(values);
    return std::move(*this);
  }
  Entry&& ros(const char* name) && {
    s.ros = name;
    return std::move(*this);
  }
  Entry&& flag(const char* cli) && {  // a bool given as a CLI flag, in CLI11's spelling
    s.cli = cli;
    s.cli_flag = true;
    return std::move(*this);
  }
  Entry&& reconfigurable(double ui_min = 0.0, double ui_max = 0.0) && {  // in Mapping.cfg
    s.reconfigurable = true;
    s.ui_min = ui_min;
    s.ui_max = ui_max;
    return std::move(*this);
  }
};

// clang-format off
std::vector<Setting> makeList() {
  const std::vector<std::string> rules(kFusionRuleNames.begin(), kFusionRuleNames.end());
  const Entry list[] = {
    // --- what a map means (stored in the .ot header) ---
    Entry("rule", &MapSettings::rule, kMap, "Fusion rule: dempster (the paper), sbki or ebs")
        .choices(rules),
    Entry("length_scale", &MapSettings::length_scale, kMap, "Kernel length scale l [m]")
        .range(kPositive).reconfigurable(0.01, 5.0),
    Entry("sigma0", &MapSettings::sigma0, kMap,
          "Kernel amplitude: a point's weight in its own voxel (dempster: its reliability)")
        .range(kPositive).reconfigurable(0.0, 1.0),
    Entry("beta", &MapSettings::beta, kMap, "Adaptive length factor beta")
        .range(kPositive).reconfigurable(0.01, 10.0),
    Entry("gamma", &MapSettings::gamma, kMap,
          "Adaptive length decay gamma (how fast the support shrinks with the uncertainty)")
        .reconfigurable(0.0, 20.0),
    Entry("drop_percent", &MapSettings::drop_percent, kMap,
          "Percentage psi of the most uncertain points dropped per scan (with the threshold on)")
        .range({0.0, 100.0, false, true, kNaN, "in [0, 100)"}).reconfigurable(0.0, 100.0),
    Entry("adaptive_length", &MapSettings::adaptive_length, kMap,
          "The paper's adaptive support l*beta*e^(1-gamma u) (off: gamma = 0, support l*beta*e; "
          "Table II ablation)")
        .flag("--adaptive-length,!--no-adaptive-length").reconfigurable(),
    Entry("uncertainty_threshold", &MapSettings::uncertainty_threshold, kMap,
          "The paper's percentile threshold: drop the drop_percent most uncertain points of each "
          "scan (Table II ablation)")
        .flag("--threshold,!--no-threshold").reconfigurable(),
    Entry("reference_compat", &MapSettings::reference_compat, kMap,
          "The authors' released configuration: gamma = 0 (support l*beta*e), count-cap "
          "down-sampling and the percentile threshold")
        .flag("--reference-compat").reconfigurable(),
    Entry("sbki_prior", &MapSettings::sbki_prior, kMap, "S-BKI prior alpha0").range(kPositive),
    Entry("evidence_cap", &MapSettings::evidence_cap, kMap,
          "dempster: read opinions with the fused log-evidence capped here: -1 follows the "
          "evidence (docs/calibration.md), 0 no cap, > 0 a fixed cap (e.g. from 'calibrate')")
        .range({0.0, kInf, false, true, MapSettings::kAdaptiveCap,
                "-1 (adaptive) or finite and >= 0 (0: no cap)"}),
    Entry("downsampling", &MapSettings::downsampling, kMap,
          "Semantic input down-sampling: average (grid of resolution/ds_multiplier) or count_cap "
          "(the authors': at most ds_multiplier+1 points per 2x2x2-voxel block)")
        .choices({"average", "count_cap"}),
    Entry("ds_multiplier", &MapSettings::ds_multiplier, kMap,
          "Down-sampling parameter (see downsampling; <= 0: off)")
        .range({-kInf, SemanticConfig::kMaxDsMultiplier, false, false, kNaN,
                "<= 1000 (<= 0: off)"})
        .reconfigurable(0.0, 50.0),
    Entry("kernel_distance", &MapSettings::kernel_distance, kMap,
          "Point-to-voxel distance of the kernel: voxel (to the voxel's cube, so a point always "
          "reaches its own voxel) or centre")
        .choices({"voxel", "centre"}),
    Entry("vertical_support", &MapSettings::vertical_support, kMap,
          "The kernel support's height as a fraction of its width (map z; 1: a ball; lower keeps "
          "ground evidence off thin upright objects)")
        .range({0.0, 1.0, true, false, kNaN, "in (0, 1]"}).reconfigurable(0.05, 1.0),
    Entry("ground_vertical_support", &MapSettings::ground_vertical_support, kMap,
          "The kernel support's height as a fraction of its width for points of ground classes "
          "(class table ground: true), so their evidence stays off what stands on the ground")
        .range({0.0, 1.0, true, false, kNaN, "in (0, 1]"}).reconfigurable(0.05, 1.0),
    Entry("max_range", &MapSettings::max_range, kMap, "Max sensor range [m] (< 0: unlimited)")
        .range({-kInf, kInf, false, false, kNaN, "a number (< 0: unlimited)"})
        .ros("sensor_model/max_range").reconfigurable(-1.0, 500.0),
    Entry("kernel_creates_leaves", &MapSettings::kernel_creates_leaves, kMap,
          "Kernel updates may create leaves in unknown space")
        .reconfigurable(),
    Entry("discretize", &MapSettings::discretize, kMap,
          "Occupancy through OctoMap's discretized ray casting (one ray per hit voxel)"),
    Entry("semantic_occupied_only", &MapSettings::semantic_occupied_only, kMap,
          "Semantic evidence only for occupied voxels and this scan's end voxels; queries "
          "elsewhere are answered from them (about half the insert CPU; not exact)"),
    // --- how an insert runs (never stored) ---
    Entry("fast_free_space", &InsertSettings::fast_free_space, kInsert,
          "Rays take a shortcut through space this scan already cleared, except where the map "
          "holds an occupied voxel or semantics (not exact; costs more than full rays once the "
          "map knows the area)"),
    Entry("evidence_floor", &InsertSettings::evidence_floor, kInsert,
          "Point evidence below this counts as 0 (0: off; 0.01 makes learned evidence about as "
          "cheap as one-hot)")
        .range({0.0, kInf, false, true, kNaN, "finite and >= 0 (0: off)"}),
    Entry("clearing_observations", &InsertSettings::clearing_observations, kInsert,
          "Clearings (rays passing through, leaving it free) after which a voxel's class evidence "
          "is gone: moving objects leave no ghosts (0: off; sequential mapping only)")
        .range({0.0, double(InsertSettings::kMaxClearingObservations), false, false, kNaN,
                "in [0, 1000] (0: off)"}),
    Entry("movable_clearing_observations", &InsertSettings::movable_clearing_observations,
          kInsert,
          "The same for the classes the class table marks movable (people, vehicles), where it "
          "comes first (0: off; sequential mapping only)")
        .range({0.0, double(InsertSettings::kMaxClearingObservations), false, false, kNaN,
                "in [0, 1000] (0: off)"}),
    Entry("other_class_weight", &InsertSettings::other_class_weight, kInsert,
          "A point's kernel weight in voxels that this scan's points show to hold other classes "
          "and not the point's (1: classes ignored; 0: the support stops there), so thin objects "
          "keep their class")
        .range({0.0, 1.0, false, false, kNaN, "in [0, 1]"}),
    Entry("threads", &InsertSettings::threads, kInsert,
          "Threads of the semantic pass (0: OpenMP default)")
        .range({0.0, double(SemanticConfig::kMaxThreads), false, false, kNaN,
                "in [0, 1024] (0: OpenMP default)"}),
  };
  std::vector<Setting> out;
  for (const Entry& e : list) out.push_back(e.s);
  return out;
}
// clang-format on

std::string joinChoices(const std::vector<std::string>& choices, const char* last) {
  std::string out;
  for (size_t i = 0; i < choices.size(); ++i) {
    if (i) out += i + 1 == choices.size() ? last : ", ";
    out += choices[i];
  }
  return out;
}

}  // namespace

bool SettingRange::contains(double v) const {
  if (!std::isnan(special) && v == special) return true;
  return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
}

const std::vector<Setting>& settingList() {
  static const std::vector<Setting> list = makeList();
  return list;
}

const Setting* findSetting(const std::string& name) {
  for (const Setting& s : settingList()) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

std::string Setting::cliName() const {
  if (cli) return cli;
  std::string out = std::string("--") + name;
  for (char& ch : out) {
    if (ch == '_') ch = '-';
  }
  return out;
}

const char* Setting::typeName() const {
  static const char* const names[] = {"bool", "int", "float", "double", "string"};
  return names[field.index()];
}

std::string Setting::valueText(const SemanticConfig& c) const {
  std::ostringstream out;
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(c.*member)>;
        if constexpr (std::is_same_v<T, bool>) {
          out << (c.*member ? "true" : "false");
        } else {
          out << c.*member;
        }
      },
      field);
  return out.str();
}

bool Setting::parse(const std::string& text, SemanticConfig* c) const {
  return std::visit(
      [&](auto member) -> bool {
        using T = std::decay_t<decltype(c->*member)>;
        if constexpr (std::is_same_v<T, bool>) {
          const bool on = text == "1" || text == "true", off = text == "0" || text == "false";
          if (on || off) c->*member = on;
          return on || off;
        } else if constexpr (std::is_same_v<T, std::string>) {
          c->*member = text;
          return !text.empty();
        } else {
          try {
            size_t used = 0;
            const double v = std::stod(text, &used);
            if constexpr (std::is_same_v<T, int>) {  // whole numbers an int holds
              if (!(v == std::floor(v) && std::abs(v) <= std::numeric_limits<int>::max()))
                return false;
            } else if constexpr (std::is_same_v<T, float>) {  // no overflow to inf
              if (std::isfinite(v) && std::abs(v) > std::numeric_limits<float>::max())
                return false;
            }
            c->*member = static_cast<T>(v);
            return used == text.size();
          } catch (const std::exception&) {
            return false;
          }
        }
      },
      field);
}

// The first value of `c` outside its setting's range or choices, "" when there is none.
std::string settingsProblem(const SemanticConfig& c) {
  for (const Setting& s : settingList()) {
    if (!s.choices.empty()) {
      const std::string& v = c.*std::get<std::string SemanticConfig::*>(s.field);
      if (std::find(s.choices.begin(), s.choices.end(), v) == s.choices.end())
        return std::string(s.name) + " '" + v + "' is unknown; use " +
               joinChoices(s.choices, " or ");
      continue;
    }
    const std::string problem = std::visit(
        [&](auto member) -> std::string {
          using T = std::decay_t<decltype(c.*member)>;
          if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
            if (s.range.contains(double(c.*member))) return "";
            std::ostringstream out;
            out << s.name << " = " << c.*member << " must be " << s.range.text;
            return out.str();
          }
          return "";
        },
        s.field);
    if (!problem.empty()) return problem;
  }
  return "";
}

std::string parameterReference() {
  const SemanticConfig defaults;
  std::ostringstream out;
  out << "# Parameters\n\n"
      << "Generated by `evidential_octomap parameters` from the one list of settings\n"
      << "(src/core/settings.cpp); a test fails when this file and the list disagree.\n\n"
      << "*map*: what a stored map means, written in its `.ot` header and read back with it.\n"
      << "*insert*: how one insert runs, never stored (it may change from scan to scan).\n"
      << "The same name is the ROS `~parameter` (unless another is given), the Python\n"
      << "`SemanticConfig` keyword and the key of `compare`'s variants (`dempster:name=value`).\n\n"
      << "| name | type | default | valid values | stored | ROS | CLI | reconfigure | help |\n"
      << "|---|---|---|---|---|---|---|---|---|\n";
  for (const Setting& s : settingList()) {
    std::string valid = s.choices.empty() ? s.range.text : joinChoices(s.choices, ", ");
    if (std::holds_alternative<bool SemanticConfig::*>(s.field)) valid = "true, false";
    std::ostringstream ui;
    if (s.reconfigurable && !std::holds_alternative<bool SemanticConfig::*>(s.field))
      ui << s.ui_min << " .. " << s.ui_max;
    else if (s.reconfigurable)
      ui << "yes";
    out << "| `" << s.name << "` | " << s.typeName() << " | " << s.valueText(defaults) << " | "
        << valid << " | " << (s.scope == SettingScope::kMap ? "map" : "insert") << " | `~"
        << s.rosName() << "` | `" << s.cliName() << "` | " << ui.str() << " | " << s.help
        << " |\n";
  }
  out << "\nOne more setting belongs to the inputs rather than the map: the evidence magnitude E "
      << "(default " << kEvidenceMagnitude << ") that\n"
      << "evidence derived from hard labels or probabilities gets for its class (ROS "
      << "`~label_evidence` and\n`~probability_evidence`, CLI `-E` and `--probability-evidence`, "
      << "Python `magnitude`).\n";
  return out.str();
}

}  // namespace evidential_octomap
