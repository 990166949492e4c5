// The one list of settings (settings.h) against what is made by hand elsewhere: the .ot header
// (every map setting stored, no insert setting), dynamic_reconfigure's ranges and defaults
// (src/ros/cfg/Mapping.cfg, Python run at build time) and the validation.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/settings.h"
#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap {
namespace {

// `c` with setting `s` moved off its default to another valid value.
SemanticConfig withOtherValue(const Setting& s) {
  SemanticConfig c;
  const SemanticConfig defaults;
  if (!s.choices.empty()) {
    for (const std::string& choice : s.choices) {
      if (choice != s.valueText(defaults)) {
        EXPECT_TRUE(s.parse(choice, &c));
      }
    }
    return c;
  }
  if (std::string(s.typeName()) == "bool") {
    EXPECT_TRUE(s.parse(s.valueText(defaults) == "true" ? "false" : "true", &c));
    return c;
  }
  const double d = std::stod(s.valueText(defaults));
  for (double v : {d + 1.0, d + 0.25, d * 0.5, 2.0, 0.5}) {
    std::ostringstream text;
    text << v;
    SemanticConfig trial;
    if (v != d && s.range.contains(v) && s.parse(text.str(), &trial) && trial.problem().empty())
      return trial;
  }
  ADD_FAILURE() << s.name << ": no other valid value found";
  return c;
}

std::unique_ptr<EvidentialOcTree> writtenAndRead(const EvidentialOcTree& tree) {
  std::stringstream file;
  EXPECT_TRUE(tree.write(file));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(file));
  auto* evidential = dynamic_cast<EvidentialOcTree*>(read.get());
  EXPECT_NE(evidential, nullptr);
  if (evidential) read.release();
  return std::unique_ptr<EvidentialOcTree>(evidential);
}

TEST(SettingList, EveryMapSettingIsStoredInTheOtFileAndNoInsertSettingIs) {
  const SemanticConfig defaults;
  for (const Setting& s : settingList()) {
    const SemanticConfig changed = withOtherValue(s);
    ASSERT_NE(s.valueText(changed), s.valueText(defaults)) << s.name;
    EvidentialOcTree tree(0.2, 3, changed);
    tree.updateNode(octomap::point3d(0.1f, 0.1f, 0.1f),
                    true);  // OctoMap skips an empty tree's data
    const auto loaded = writtenAndRead(tree);
    ASSERT_TRUE(loaded) << s.name;
    const std::string expected =
        s.scope == SettingScope::kMap ? s.valueText(changed) : s.valueText(defaults);
    EXPECT_EQ(s.valueText(loaded->config()), expected)
        << s.name
        << (s.scope == SettingScope::kMap ? ": a map setting the .ot file loses"
                                          : ": an insert setting the .ot file keeps");
  }
}

TEST(SettingList, NamesAreUniqueAndEveryDefaultIsValid) {
  std::set<std::string> names, cli;
  const SemanticConfig defaults;
  for (const Setting& s : settingList()) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_TRUE(cli.insert(s.cliName()).second) << s.cliName();
    EXPECT_EQ(findSetting(s.name), &s);
    if (s.choices.empty() && std::string(s.typeName()) != "bool" &&
        std::string(s.typeName()) != "string") {
      EXPECT_TRUE(s.range.contains(std::stod(s.valueText(defaults)))) << s.name;
    }
  }
  EXPECT_EQ(defaults.problem(), "");
  EXPECT_EQ(findSetting("no_such_setting"), nullptr);
}

TEST(SettingList, AValueOutsideItsRangeIsRefusedNamingTheSetting) {
  for (const Setting& s : settingList()) {
    SemanticConfig c;
    if (!s.choices.empty()) {
      ASSERT_TRUE(s.parse("no_such_choice", &c));
    } else if (std::string(s.typeName()) == "bool") {
      EXPECT_FALSE(s.parse("maybe", &c)) << s.name;
      continue;
    } else {  // the first of these values that the type holds and the range refuses
      bool outside = false;
      for (const char* v : {"nan", "-1", "-1e300", "1e300"}) {
        SemanticConfig trial;
        if (s.parse(v, &trial) && !s.range.contains(std::stod(s.valueText(trial)))) {
          c = trial;
          outside = true;
          break;
        }
      }
      ASSERT_TRUE(outside) << s.name;
    }
    const std::string problem = c.problem();
    EXPECT_EQ(problem.rfind(s.name, 0), 0u) << s.name << ": " << problem;
  }
}

// sem.add("name", double_t, 0, "help", default, min, max) lines of Mapping.cfg.
struct CfgEntry {
  std::string type, default_text;
  double min = NAN, max = NAN;
};
std::map<std::string, CfgEntry> reconfigureEntries() {
  std::ifstream in(std::string(EVIDENTIAL_OCTOMAP_SOURCE_DIR) + "/src/ros/cfg/Mapping.cfg");
  EXPECT_TRUE(in.good());
  const std::regex line(
      R"re(^\w+\.add\("(\w+)",\s*(\w+),\s*0,\s*"[^"]*",\s*([^,)]+)(?:,\s*([^,)]+),\s*([^,)]+))?\))re");
  std::map<std::string, CfgEntry> out;
  for (std::string text; std::getline(in, text);) {
    std::smatch m;
    if (!std::regex_search(text, m, line)) continue;
    CfgEntry e{m[2], m[3]};
    if (m[4].matched) e.min = std::stod(m[4]), e.max = std::stod(m[5]);
    out[m[1]] = e;
  }
  return out;
}

TEST(SettingList, DynamicReconfigureRangesAndDefaultsAreTheList) {
  auto entries = reconfigureEntries();
  ASSERT_FALSE(entries.empty());
  const SemanticConfig defaults;
  for (const Setting& s : settingList()) {
    std::string name = s.rosName();
    for (char& ch : name) {
      if (ch == '/') ch = '_';
    }
    const auto it = entries.find(name);
    EXPECT_EQ(it != entries.end(), s.reconfigurable) << name << " in Mapping.cfg";
    if (it == entries.end()) continue;
    const CfgEntry& e = it->second;
    if (std::string(s.typeName()) == "bool") {
      EXPECT_EQ(e.type, "bool_t") << name;
      EXPECT_EQ(e.default_text, s.valueText(defaults) == "true" ? "True" : "False") << name;
    } else {
      EXPECT_EQ(e.type, "double_t") << name;
      EXPECT_EQ(std::stod(e.default_text), std::stod(s.valueText(defaults))) << name;
      EXPECT_EQ(e.min, s.ui_min) << name;
      EXPECT_EQ(e.max, s.ui_max) << name;
    }
    entries.erase(it);
  }
  // What is left belongs to the sensor model and the node's outputs, not to SemanticConfig.
  for (const auto& [name, e] : entries) {
    EXPECT_TRUE(name.rfind("sensor_model_", 0) == 0 || name == "publish_rate" ||
                name == "label_evidence")
        << name << ": a reconfigurable setting the list does not have";
  }
  ASSERT_EQ(reconfigureEntries().count("label_evidence"), 1u);
  EXPECT_EQ(std::stod(reconfigureEntries()["label_evidence"].default_text), kEvidenceMagnitude);
}

TEST(SettingList, TextRoundTripsForEverySetting) {
  for (const Setting& s : settingList()) {
    const SemanticConfig changed = withOtherValue(s);
    SemanticConfig parsed;
    ASSERT_TRUE(s.parse(s.valueText(changed), &parsed)) << s.name;
    EXPECT_EQ(s.valueText(parsed), s.valueText(changed)) << s.name;
  }
  SemanticConfig c;
  EXPECT_FALSE(findSetting("threads")->parse("1.5", &c));
  EXPECT_FALSE(findSetting("length_scale")->parse("0.3m", &c));
}

}  // namespace
}  // namespace evidential_octomap
