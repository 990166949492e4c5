// The one class table: names, colours and the raw-label -> class map of a dataset, read from
// config/classes_*.yaml. Everything that prints or draws a class reads it; C comes from here.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace evidential_octomap {

struct ClassTable {
  using Rgb = std::array<uint8_t, 3>;

  std::string dataset;               // e.g. "semantickitti"
  std::vector<std::string> names;    // C class names, index = class id
  std::vector<Rgb> colors;           // C colours (RGB)
  // C flags: the class is a ground surface (`ground: true`; road, trail, grass): its points'
  // kernel support is flatter (SemanticConfig::ground_vertical_support).
  std::vector<bool> ground;
  // C flags: the class moves (`movable: true`; people, vehicles): a voxel that rays find empty
  // again forgets it (SemanticConfig::movable_clearing_observations).
  std::vector<bool> movable;
  int ignore_class = -1;             // class excluded from evaluation queries (-1: none)
  std::unordered_map<uint32_t, int> learning_map;  // raw label id -> class id

  int numClasses() const { return static_cast<int>(names.size()); }
  // Class of a raw label (the lower 16 bits are used). Throws std::out_of_range naming the id
  // when the label is not in the learning map.
  int classOfRaw(uint32_t raw_label) const;

  // Reads a YAML class table; throws std::runtime_error naming the file and the problem.
  static ClassTable load(const std::string& yaml_path);
};

}  // namespace evidential_octomap
