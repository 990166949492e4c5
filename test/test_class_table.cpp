// The class table (config/classes_*.yaml): names, colours, ignore class and learning map.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "evidential_octomap/class_table.h"

namespace evidential_octomap {
namespace {

const std::string kSourceDir = EVIDENTIAL_OCTOMAP_SOURCE_DIR;
const std::string kFixtures = kSourceDir + "/test/fixtures/";

// Expects `f` to throw E whose message contains every string in `parts`.
template <typename E, typename F>
void expectThrowNaming(F f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no exception";
  } catch (const E& e) {
    const std::string msg = e.what();
    for (const auto& part : parts) EXPECT_NE(msg.find(part), std::string::npos) << msg;
  }
}

TEST(ClassTable, SemanticKittiTableHasTwentyClasses) {
  const ClassTable table = ClassTable::load(kSourceDir + "/config/classes_semantickitti.yaml");
  EXPECT_EQ(table.dataset, "semantickitti");
  EXPECT_EQ(table.numClasses(), 20);
  EXPECT_EQ(table.colors.size(), 20u);
  EXPECT_EQ(table.ignore_class, 0);
  EXPECT_EQ(table.names[0], "unlabeled");
  EXPECT_EQ(table.names[1], "car");
}

TEST(ClassTable, SemanticKittiLearningMap) {
  const ClassTable table = ClassTable::load(kSourceDir + "/config/classes_semantickitti.yaml");
  EXPECT_EQ(table.classOfRaw(10), 1);   // car
  EXPECT_EQ(table.classOfRaw(252), 1);  // moving-car -> car
  EXPECT_EQ(table.classOfRaw(0), 0);    // unlabeled
  EXPECT_EQ(table.classOfRaw(40), 9);   // road
  // The upper 16 bits of a SemanticKITTI label are the instance id and are ignored.
  EXPECT_EQ(table.classOfRaw((7u << 16) | 10u), 1);
  EXPECT_EQ(table.classOfRaw((123u << 16) | 252u), 1);
}

TEST(ClassTable, UnknownRawIdThrowsNamingTheId) {
  const ClassTable table = ClassTable::load(kSourceDir + "/config/classes_semantickitti.yaml");
  expectThrowNaming<std::out_of_range>([&] { table.classOfRaw(12345); }, {"12345"});
  expectThrowNaming<std::out_of_range>([&] { table.classOfRaw(2); }, {"2"});
}

TEST(ClassTable, Rellis3dTableIsConsistent) {
  const ClassTable table = ClassTable::load(kSourceDir + "/config/classes_rellis3d.yaml");
  EXPECT_GT(table.numClasses(), 1);
  EXPECT_EQ(table.colors.size(), table.names.size());
  for (const auto& [raw, cls] : table.learning_map) {
    EXPECT_GE(cls, 0) << "raw " << raw;
    EXPECT_LT(cls, table.numClasses()) << "raw " << raw;
  }
}

TEST(ClassTable, SmallFixtureIsReadExactly) {
  const ClassTable table = ClassTable::load(kFixtures + "classes_small.yaml");
  EXPECT_EQ(table.dataset, "small");
  ASSERT_EQ(table.numClasses(), 3);
  EXPECT_EQ(table.names[0], "ground");
  EXPECT_EQ(table.names[1], "tree");
  EXPECT_EQ(table.names[2], "unknown");
  EXPECT_EQ(table.colors[0], (ClassTable::Rgb{10, 20, 30}));
  EXPECT_EQ(table.colors[1], (ClassTable::Rgb{0, 255, 0}));
  EXPECT_EQ(table.ignore_class, 2);
  EXPECT_EQ(table.ground, (std::vector<bool>{true, false, false})) << "left out means false";
  EXPECT_EQ(table.movable, (std::vector<bool>{false, true, false}));
  EXPECT_EQ(table.learning_map.size(), 3u);
  EXPECT_EQ(table.classOfRaw(0), 2);
  EXPECT_EQ(table.classOfRaw(7), 0);
  EXPECT_EQ(table.classOfRaw(300), 1);
  EXPECT_THROW(table.classOfRaw(8), std::out_of_range);
}

TEST(ClassTable, MalformedYamlThrowsNamingTheFile) {
  const std::string path = kFixtures + "classes_malformed.yaml";
  expectThrowNaming<std::runtime_error>([&] { ClassTable::load(path); }, {path});
}

TEST(ClassTable, BadColourThrowsNamingFileAndClass) {
  const std::string path = kFixtures + "classes_bad_color.yaml";
  expectThrowNaming<std::runtime_error>([&] { ClassTable::load(path); }, {path, "ground"});
}

TEST(ClassTable, MappingToMissingClassThrowsNamingTheFile) {
  const std::string path = kFixtures + "classes_bad_mapping.yaml";
  expectThrowNaming<std::runtime_error>([&] { ClassTable::load(path); }, {path, "7"});
}

TEST(ClassTable, MissingClassListThrowsNamingTheFile) {
  const std::string path = kFixtures + "classes_no_classes.yaml";
  expectThrowNaming<std::runtime_error>([&] { ClassTable::load(path); }, {path});
}

TEST(ClassTable, GroundFlagThatIsNotABooleanThrowsNamingTheFile) {
  const std::string path = kFixtures + "classes_bad_ground.yaml";
  expectThrowNaming<std::runtime_error>([&] { ClassTable::load(path); }, {path, "maybe"});
}

// The names of the classes whose flag is set.
std::vector<std::string> namesWhere(const ClassTable& table, const std::vector<bool>& flags) {
  std::vector<std::string> names;
  for (int c = 0; c < table.numClasses(); ++c) {
    if (flags[c]) names.push_back(table.names[c]);
  }
  return names;
}

TEST(ClassTable, ShippedTablesMarkTheirGroundSurfaces) {
  const ClassTable kitti = ClassTable::load(kSourceDir + "/config/classes_semantickitti.yaml");
  EXPECT_EQ(namesWhere(kitti, kitti.ground),
            (std::vector<std::string>{"road", "parking", "sidewalk", "other-ground", "terrain"}));
}

TEST(ClassTable, ShippedTablesMarkPeopleAndVehiclesMovable) {
  const ClassTable kitti = ClassTable::load(kSourceDir + "/config/classes_semantickitti.yaml");
  EXPECT_EQ(namesWhere(kitti, kitti.movable),
            (std::vector<std::string>{"car", "bicycle", "motorcycle", "truck", "other-vehicle",
                                      "person", "bicyclist", "motorcyclist"}));
  for (const char* family : {"rellis3d", "offroad_farm", "offroad_forest", "offroad_grassland",
                             "offroad_rocky"}) {
    const ClassTable table =
        ClassTable::load(kSourceDir + "/config/classes_" + std::string(family) + ".yaml");
    for (int c = 0; c < table.numClasses(); ++c) {
      const bool mover = table.names[c] == "person" || table.names[c] == "vehicle";
      EXPECT_EQ(table.movable[c], mover) << family << " " << table.names[c];
    }
  }
}

TEST(ClassTable, MissingFileThrowsNamingThePath) {
  const std::string path = kFixtures + "does_not_exist.yaml";
  expectThrowNaming<std::runtime_error>([&] { ClassTable::load(path); }, {path});
}

}  // namespace
}  // namespace evidential_octomap
