// What a surface is made of: the generator's ground-truth vocabulary. Each kind has its
// RELLIS-3D-ontology raw label id (the family's class table maps it to a class), a LiDAR
// reflectivity, and the network model's rarity and confusion partners.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "evidential_octomap/class_table.h"

namespace evidential_octomap::generator {

enum class Kind : uint8_t {
  kVoid,
  kDirt,
  kGrass,
  kTree,
  kBush,
  kLog,
  kMud,
  kPuddle,
  kPerson,
  kVehicle,
  kGravel,
  kRock,
  kBoulder,
  kFence,
  kPole,
  kBuilding,
  kConcrete,
  kCount
};
constexpr int kNumKinds = int(Kind::kCount);

struct KindInfo {
  const char* name;
  uint32_t raw_id;               // raw label id written to labels/ (RELLIS-3D's where it has one)
  float reflectivity;            // diffuse reflectivity at 865 nm, [0, 1]
  float rarity;                  // network model: added difficulty of the class (rare, thin)
  std::array<Kind, 3> partners;  // network model: the classes it is confused with, in order
};

const KindInfo& kindInfo(Kind k);

enum class Family { kForest, kGrassland, kRocky, kFarm };
Family parseFamily(const std::string& name);  // throws std::invalid_argument
const char* familyName(Family f);

// The family's class table (config/classes_offroad_<family>.yaml, embedded at build time).
const std::string& classTableYaml(Family f);

// Kind -> class id of a family's table (through the learning map of its raw id), and each
// kind's first confusion partner that the family has (-1: none).
struct KindClasses {
  std::array<int, kNumKinds> cls;
  std::array<int, kNumKinds> partner;
  std::vector<uint32_t> raw_of_class;  // class id -> the raw id written for predictions
  static KindClasses of(const ClassTable& table);
};

}  // namespace evidential_octomap::generator
