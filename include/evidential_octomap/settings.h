// The one declarative list of the semantic-mapping settings: name, type, default (the struct's
// in-class value), valid range, whether a stored map keeps it, help, and its ROS / CLI names.
// The validation (SemanticConfig::problem), the ROS ~parameters, the CLI options, `compare`'s
// variant keys, the Python keyword arguments and docs/parameters.md are all made from it; a test
// checks dynamic_reconfigure's ranges and defaults (src/ros/cfg/Mapping.cfg) and the .ot header
// (every map setting stored, no insert setting) against it.
//
// Adding a setting: a field in MapSettings or InsertSettings (semantic_config.h) and ONE line in
// settingList() (src/core/settings.cpp); then regenerate docs/parameters.md
// (`evidential_octomap parameters > docs/parameters.md`). A map setting must also be written and
// read in the .ot header (ot_format.cpp): the file format is explicit, so that reordering this
// list never changes it, and test_settings fails until it is.
#pragma once

#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

// kMap: what a stored map means (written in the .ot header, a property of the map);
// kInsert: how one insert runs (never stored; may differ from insert to insert).
enum class SettingScope { kMap, kInsert };

using SettingField =
    std::variant<bool SemanticConfig::*, int SemanticConfig::*, float SemanticConfig::*,
                 double SemanticConfig::*, std::string SemanticConfig::*>;

// Valid values of a number: lo < / <= v < / <= hi (NaN never), or v == special when special is
// not NaN. `text` says it in words, as the error messages do.
struct SettingRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = true, hi_open = true;
  double special = std::numeric_limits<double>::quiet_NaN();
  const char* text = "finite";
  bool contains(double v) const;
};

struct Setting {
  const char* name = nullptr;  // the field, Python keyword, compare variant key and ROS ~param
  SettingField field;
  SettingScope scope = SettingScope::kMap;
  const char* help = nullptr;
  SettingRange range;                // numbers
  std::vector<std::string> choices;  // strings: the values allowed
  const char* ros = nullptr;         // the ~param when it is not `name`
  const char* cli = nullptr;         // CLI11 spelling when it is not --name-with-dashes
  bool cli_flag = false;             // a bool given as a flag (else --x true/false)
  // dynamic_reconfigure slider range (src/ros/cfg/Mapping.cfg), when the node exposes it.
  bool reconfigurable = false;
  double ui_min = 0.0, ui_max = 0.0;

  std::string rosName() const { return ros ? ros : name; }
  std::string cliName() const;  // e.g. "--length-scale"
  // The value of this setting in `c`, printed as the CLI and the docs print it.
  std::string valueText(const SemanticConfig& c) const;
  // Sets it from text ("0"/"1"/"true"/"false" for bools); false when the text is no value of
  // this type (ranges are checked by SemanticConfig::problem).
  bool parse(const std::string& text, SemanticConfig* c) const;
  const char* typeName() const;  // "bool", "int", "float", "double", "string"
};

// Every setting of SemanticConfig, map settings first, in the order problem() checks them.
const std::vector<Setting>& settingList();
const Setting* findSetting(const std::string& name);  // nullptr when there is none
// The first value of `c` outside its setting's range or choices ("name = v must be <range>"),
// "" when there is none: the per-setting part of SemanticConfig::problem().
std::string settingsProblem(const SemanticConfig& c);

// docs/parameters.md: every setting's type, default, range, scope, names and help.
std::string parameterReference();

}  // namespace evidential_octomap
