// A minimal JSON writer for the bench results (ordered keys, numbers, strings, arrays).
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace evbench {

class Json {
 public:
  static Json object() { return Json('{'); }
  static Json array() { return Json('['); }

  Json& set(const std::string& key, const Json& value) { return add(quote(key) + ": " + value.str()); }
  Json& set(const std::string& key, double value) { return add(quote(key) + ": " + number(value)); }
  Json& set(const std::string& key, int value) { return add(quote(key) + ": " + std::to_string(value)); }
  Json& set(const std::string& key, size_t value) {
    return add(quote(key) + ": " + std::to_string(value));
  }
  Json& set(const std::string& key, bool value) {
    return add(quote(key) + ": " + (value ? "true" : "false"));
  }
  Json& set(const std::string& key, const std::string& value) {
    return add(quote(key) + ": " + quote(value));
  }
  Json& set(const std::string& key, const char* value) { return set(key, std::string(value)); }
  Json& set(const std::string& key, const std::vector<double>& values) {
    Json a = array();
    for (double v : values) a.push(v);
    return set(key, a);
  }
  Json& push(const Json& value) { return add(value.str()); }
  Json& push(double value) { return add(number(value)); }

  std::string str(int indent = 0) const {
    (void)indent;
    std::string out(1, open_);
    for (size_t i = 0; i < items_.size(); ++i) out += (i ? ", " : "") + items_[i];
    out += open_ == '{' ? '}' : ']';
    return out;
  }

  static std::string number(double v) {
    if (!std::isfinite(v)) return "null";
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.6g", v);
    return buffer;
  }
  static std::string quote(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
      if (c == '"' || c == '\\') out += '\\';
      if (c == '\n') {
        out += "\\n";
        continue;
      }
      out += c;
    }
    return out + "\"";
  }

 private:
  explicit Json(char open) : open_(open) {}
  Json& add(std::string item) {
    items_.push_back(std::move(item));
    return *this;
  }
  char open_;
  std::vector<std::string> items_;
};

}  // namespace evbench
