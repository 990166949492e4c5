// A bench's settings rows on its command line: LABEL:defaults|FILE.yaml[:key=value,...], where
// FILE is a flat `key: value  # comment` profile such as config/mapping_live.yaml and each
// override goes through the one list of settings (settings.h).
#pragma once

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "evidential_octomap/semantic_config.h"
#include "evidential_octomap/settings.h"

namespace evbench {

struct SettingsRow {
  std::string label;
  evidential_octomap::SemanticConfig config;
};

inline void applySetting(const std::string& name, const std::string& value,
                         evidential_octomap::SemanticConfig* config) {
  if (name == "settings_profile") return;  // names the profile, not a setting
  const evidential_octomap::Setting* s = evidential_octomap::findSetting(name);
  if (!s || !s->parse(value, config))
    throw std::invalid_argument("no setting " + name + " = " + value);
}

inline std::string trimmed(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

inline void readProfile(const std::string& path, evidential_octomap::SemanticConfig* config) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot read " + path);
  for (std::string line; std::getline(in, line);) {
    line = trimmed(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) throw std::invalid_argument(path + ": not key: value: " + line);
    applySetting(trimmed(line.substr(0, colon)), trimmed(line.substr(colon + 1)), config);
  }
}

inline SettingsRow parseSettingsRow(const std::string& arg) {
  std::vector<std::string> parts;
  std::stringstream s(arg);
  for (std::string p; std::getline(s, p, ':');) parts.push_back(p);
  if (parts.size() < 2) throw std::invalid_argument("row is LABEL:defaults|FILE[:k=v,...]: " + arg);
  SettingsRow row{parts[0], evidential_octomap::SemanticConfig()};
  if (parts[1] != "defaults") readProfile(parts[1], &row.config);
  if (parts.size() > 2) {
    std::stringstream kv(parts[2]);
    for (std::string item; std::getline(kv, item, ',');) {
      const size_t eq = item.find('=');
      if (eq == std::string::npos) throw std::invalid_argument("override is key=value: " + item);
      applySetting(item.substr(0, eq), item.substr(eq + 1), &row.config);
    }
  }
  const std::string problem = row.config.problem();
  if (!problem.empty()) throw std::invalid_argument(row.label + ": " + problem);
  return row;
}

}  // namespace evbench
