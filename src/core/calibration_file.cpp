#include "evidential_octomap/calibration_file.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

namespace {

std::string trimmed(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

std::string unquoted(const std::string& s) {
  const bool quoted = s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front();
  return quoted ? s.substr(1, s.size() - 2) : s;
}

// `[a, b, "c d"]` -> its items; throws std::invalid_argument when not a flow list.
std::vector<std::string> flowList(const std::string& value) {
  if (value.size() < 2 || value.front() != '[' || value.back() != ']') {
    throw std::invalid_argument("expected a list in brackets, [a, b, ...]");
  }
  std::vector<std::string> items;
  std::string item;
  char quote = 0;
  for (const char c : value.substr(1, value.size() - 2)) {
    if (quote == 0 && c == ',') {
      items.push_back(unquoted(trimmed(item)));
      item.clear();
      continue;
    }
    if (c == '"' || c == '\'') quote = quote == c ? 0 : (quote == 0 ? c : quote);
    item += c;
  }
  if (!trimmed(item).empty() || !items.empty()) items.push_back(unquoted(trimmed(item)));
  return items;
}

double number(const std::string& text) {
  size_t used = 0;
  double value = NAN;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) throw std::invalid_argument("'" + text + "' is not a number");
  return value;
}

// A name as a flow-list item: bare unless YAML would read it otherwise.
std::string listItem(const std::string& name) {
  const bool plain = !name.empty() && name.find_first_of(",[]{}:#\"'&*!|>%@` ") == std::string::npos;
  return plain ? name : "\"" + name + "\"";
}

template <class T, class F>
std::string flow(const std::vector<T>& items, F&& text) {
  std::string out = "[";
  for (size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + text(items[i]);
  return out + "]";
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::string Calibration::problemWith(const std::vector<std::string>& class_names,
                                     const std::string& rule_name) const {
  if (rule_name != rule) {
    return source + ": the calibration was fitted for the " + rule +
           " rule; this map fuses with " + rule_name + " (refit with `evidential_octomap "
           "calibrate` for that rule, or map with the rule it was fitted for)";
  }
  if (!classes.empty() && classes != class_names) {
    return source + ": the calibration was fitted for " + std::to_string(classes.size()) +
           " classes [" + joined(classes) + "]; this map has " +
           std::to_string(class_names.size()) + " [" + joined(class_names) +
           "] (calibrate with the class table you map with)";
  }
  return "";
}

Calibration makeCalibration(int version, const std::string& rule,
                            const std::vector<std::string>& classes, double evidence_cap,
                            const std::vector<std::string>& terms,
                            const std::vector<double>& weights, const std::string& source) {
  if (version < 1 || version > Calibration::kVersion) {
    throw std::runtime_error(source + ": calibration_version " + std::to_string(version) +
                             " is not one this build reads (1 to " +
                             std::to_string(Calibration::kVersion) +
                             "; a newer evidential_octomap wrote it?)");
  }
  const bool adaptive = evidence_cap == SemanticConfig::kAdaptiveCap;
  if (!std::isfinite(evidence_cap) || (evidence_cap < 0.0 && !adaptive)) {
    throw std::runtime_error(source + ": evidence_cap must be -1 (adaptive) or a finite number "
                             ">= 0");
  }
  Calibration c;
  c.version = version;
  c.rule = rule;
  c.classes = classes;
  c.evidence_cap = evidence_cap;
  c.source = source;
  if (terms.empty() && weights.empty()) return c;
  try {
    c.error_model = std::make_shared<const ErrorModel>(terms, weights);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(source + ": " + e.what());
  }
  return c;
}

Calibration readCalibration(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read the calibration file");
  std::map<std::string, std::string> values;
  std::map<std::string, int> line_of;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    line = trimmed(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    const size_t colon = line.find(':');
    const std::string where = path + ":" + std::to_string(n) + ": ";
    if (colon == std::string::npos) throw std::runtime_error(where + "expected `key: value`");
    const std::string key = trimmed(line.substr(0, colon));
    static const char* kKeys[] = {"calibration_version", "calibration_rule", "calibration_classes",
                                  "evidence_cap", "error_model_terms", "error_model_weights"};
    if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys)) {
      throw std::runtime_error(where + "unknown key '" + key + "' (a calibration file holds " +
                               "evidence_cap and the error model, as written by " +
                               "`evidential_octomap calibrate`)");
    }
    values[key] = trimmed(line.substr(colon + 1));
    line_of[key] = n;
  }
  const auto at = [&](const std::string& key) {
    return path + ":" + std::to_string(line_of[key]) + ": ";
  };
  if (!values.count("evidence_cap")) {
    throw std::runtime_error(path + ": no evidence_cap in the calibration file");
  }
  double cap = NAN;
  try {
    cap = number(values["evidence_cap"]);
  } catch (const std::invalid_argument&) {
  }
  if (!std::isfinite(cap) || (cap < 0.0 && cap != SemanticConfig::kAdaptiveCap)) {
    throw std::runtime_error(at("evidence_cap") + "evidence_cap must be -1 (adaptive) or a finite "
                             "number >= 0, not '" + values["evidence_cap"] + "'");
  }
  try {
    const int version = values.count("calibration_version")
                            ? int(number(values["calibration_version"]))
                            : 1;
    std::vector<std::string> classes, terms;
    std::vector<double> weights;
    if (values.count("calibration_classes")) classes = flowList(values["calibration_classes"]);
    if (values.count("error_model_terms")) terms = flowList(values["error_model_terms"]);
    if (values.count("error_model_weights")) {
      for (const std::string& w : flowList(values["error_model_weights"])) weights.push_back(number(w));
    }
    const std::string rule =
        values.count("calibration_rule") ? unquoted(values["calibration_rule"]) : "dempster";
    return makeCalibration(version, rule, classes, cap, terms, weights, path);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

std::string calibrationText(const Calibration& c, const std::string& comment) {
  std::ostringstream file;
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) file << "# " << line << "\n";
  file.precision(10);
  file << "calibration_version: " << Calibration::kVersion << "\n"
       << "calibration_rule: " << c.rule << "\n"
       << "calibration_classes: " << flow(c.classes, listItem) << "\n"
       << "evidence_cap: " << c.evidence_cap << "\n";
  if (c.error_model) {
    file << "error_model_terms: " << flow(c.error_model->terms(), listItem) << "\n"
         << "error_model_weights: "
         << flow(c.error_model->weights(), [](double w) {
              std::ostringstream s;
              s.precision(10);
              s << w;
              return s.str();
            })
         << "\n";
  }
  return file.str();
}

void applyCalibration(const Calibration& calibration, EvidentialOcTree* tree) {
  const std::string problem = calibration.problemWith(tree->classNames(), tree->rule().name());
  if (!problem.empty()) throw std::runtime_error(problem);
  SemanticConfig config = tree->config();
  config.evidence_cap = calibration.evidence_cap;
  tree->setConfig(config);
  tree->setErrorModel(calibration.error_model);
}

}  // namespace evidential_octomap
