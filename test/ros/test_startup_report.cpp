// The start-up report names the profile, lists the costly settings against the offline
// defaults, and warns only for a live topic mapped without a profile.
#include <gtest/gtest.h>

#include "startup_report.h"

namespace evidential_octomap {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(StartupReport, NamesTheProfileAndTheChangedSettings) {
  SemanticConfig live;
  live.length_scale = 0.2;
  live.fast_free_space = true;
  live.semantic_occupied_only = true;
  bool warn = true;
  const std::string report = settingsReport("live", live, true, &warn);
  EXPECT_FALSE(warn);
  EXPECT_TRUE(contains(report, "settings profile: live")) << report;
  EXPECT_TRUE(contains(report, "length_scale 0.2 (offline 0.3)")) << report;
  EXPECT_TRUE(contains(report, "fast_free_space true (offline false)")) << report;
  EXPECT_TRUE(contains(report, "semantic_occupied_only true (offline false)")) << report;
  EXPECT_TRUE(contains(report, "ds_multiplier 5,")) << report;  // unchanged: no "(offline"
}

TEST(StartupReport, WarnsForALiveTopicWithTheOfflineDefaults) {
  bool warn = false;
  const std::string report = settingsReport("", SemanticConfig(), true, &warn);
  EXPECT_TRUE(warn);
  EXPECT_TRUE(contains(report, "offline defaults")) << report;
  EXPECT_TRUE(contains(report, "mapping_live.yaml")) << report;
}

TEST(StartupReport, NoWarningOnSimulatedTime) {
  bool warn = true;
  settingsReport("", SemanticConfig(), false, &warn);
  EXPECT_FALSE(warn);
}

}  // namespace
}  // namespace evidential_octomap

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
