#include "evidential_octomap/class_table.h"

#include <yaml-cpp/yaml.h>

#include <stdexcept>

namespace evidential_octomap {

int ClassTable::classOfRaw(uint32_t raw_label) const {
  const auto it = learning_map.find(raw_label & 0xFFFFu);
  if (it == learning_map.end()) {
    throw std::out_of_range("raw label id " + std::to_string(raw_label & 0xFFFFu) +
                            " is not in the " + dataset + " learning map");
  }
  return it->second;
}

ClassTable ClassTable::load(const std::string& yaml_path) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("class table " + yaml_path + ": " + why);
  };
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::BadFile&) {
    throw fail("cannot open file");
  } catch (const YAML::Exception& e) {
    throw fail(std::string("not valid YAML: ") + e.what());
  }
  ClassTable table;
  // A class's yes/no property (ground, movable): false when left out.
  const auto readFlag = [&](const YAML::Node& entry, const std::string& key) {
    bool value = false;
    const YAML::Node flag = entry[key];
    if (flag && !YAML::convert<bool>::decode(flag, value)) {
      throw fail("class '" + table.names.back() + "': " + key + " must be true or false, not '" +
                 flag.as<std::string>() + "'");
    }
    return value;
  };
  try {
    table.dataset = root["dataset"] ? root["dataset"].as<std::string>() : "unnamed";
    const YAML::Node classes = root["classes"];
    if (!classes || !classes.IsSequence() || classes.size() == 0) {
      throw fail("needs a non-empty 'classes' list");
    }
    if (classes.size() > 255) throw fail("more than 255 classes");
    for (const auto& entry : classes) {
      table.names.push_back(entry["name"].as<std::string>());
      const YAML::Node color = entry["color"];
      if (!color || !color.IsSequence() || color.size() != 3) {
        throw fail("class '" + table.names.back() + "' needs color: [r, g, b]");
      }
      Rgb rgb;
      for (int i = 0; i < 3; ++i) {
        const int v = color[i].as<int>();
        if (v < 0 || v > 255) throw fail("colour of '" + table.names.back() + "' out of 0..255");
        rgb[i] = static_cast<uint8_t>(v);
      }
      table.colors.push_back(rgb);
      table.ground.push_back(readFlag(entry, "ground"));
      table.movable.push_back(readFlag(entry, "movable"));
    }
    table.ignore_class = root["ignore_class"] ? root["ignore_class"].as<int>() : -1;
    if (table.ignore_class >= table.numClasses()) throw fail("ignore_class out of range");
    if (const YAML::Node map = root["learning_map"]) {
      for (const auto& pair : map) {
        const int cls = pair.second.as<int>();
        if (cls < 0 || cls >= table.numClasses()) {
          throw fail("learning_map sends raw id " + pair.first.as<std::string>() +
                     " to class " + std::to_string(cls) + ", outside 0.." +
                     std::to_string(table.numClasses() - 1));
        }
        table.learning_map[pair.first.as<uint32_t>()] = cls;
      }
    }
  } catch (const YAML::Exception& e) {
    throw fail(std::string("malformed entry: ") + e.what());
  }
  return table;
}

}  // namespace evidential_octomap
