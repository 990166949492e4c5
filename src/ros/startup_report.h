// The node's first words about its settings: which profile it runs with (the code's offline
// defaults or a named profile such as config/mapping_live.yaml), the settings that cost the most
// CPU, and a warning when a live sensor is mapped with the offline defaults (a plain rosrun).
#pragma once

#include <string>

#include <ros/node_handle.h>

#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

// The report for `profile` ("" = none named: the offline defaults) with the settings in use.
// live_topic: the clouds come from a running sensor (not simulated time). *warn is set when the
// report is a warning: a live topic mapped with the offline profile.
std::string settingsReport(const std::string& profile, const SemanticConfig& in_use,
                           bool live_topic, bool* warn);

// Logs settingsReport for ~settings_profile and ros::Time::isSimTime(), and leaves it in
// ~settings_report.
void reportSettingsProfile(ros::NodeHandle& pnh, const SemanticConfig& in_use);

}  // namespace evidential_octomap
