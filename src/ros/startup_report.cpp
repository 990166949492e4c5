#include "startup_report.h"

#include <sstream>

#include <ros/console.h>
#include <ros/time.h>

namespace evidential_octomap {

namespace {

// "name value", with "(offline x)" when it differs from the code's default.
template <typename T>
void describe(std::ostringstream& s, const char* name, T in_use, T offline) {
  s << (s.tellp() > 0 ? ", " : "") << name << " " << in_use;
  if (in_use != offline) s << " (offline " << offline << ")";
}

}  // namespace

std::string settingsReport(const std::string& profile, const SemanticConfig& in_use,
                           bool live_topic, bool* warn) {
  const SemanticConfig offline;
  std::ostringstream values;
  values << std::boolalpha;
  describe(values, "length_scale", in_use.length_scale, offline.length_scale);
  describe(values, "ds_multiplier", in_use.ds_multiplier, offline.ds_multiplier);
  describe(values, "evidence_floor", in_use.evidence_floor, offline.evidence_floor);
  describe(values, "fast_free_space", in_use.fast_free_space, offline.fast_free_space);
  describe(values, "semantic_occupied_only", in_use.semantic_occupied_only,
           offline.semantic_occupied_only);

  std::ostringstream s;
  *warn = profile.empty() && live_topic;
  if (profile.empty())
    s << "settings: the offline defaults of the code (no ~settings_profile); " << values.str();
  else
    s << "settings profile: " << profile << "; " << values.str();
  if (*warn)
    s << ". A live topic (no simulated time) is mapped with the offline defaults, which cost "
         "several times the insert CPU of the live profile (docs/ros.md): roslaunch evidential_octomap "
         "mapping.launch, or load config/mapping_live.yaml (set ~settings_profile to name a "
         "profile of your own).";
  return s.str();
}

void reportSettingsProfile(ros::NodeHandle& pnh, const SemanticConfig& in_use) {
  std::string profile;
  pnh.param<std::string>("settings_profile", profile, "");
  bool warn = false;
  const std::string report = settingsReport(profile, in_use, !ros::Time::isSimTime(), &warn);
  if (warn)
    ROS_WARN("%s", report.c_str());
  else
    ROS_INFO("%s", report.c_str());
  pnh.setParam("settings_report", report);  // for `rosparam get` after the log has scrolled by
}

}  // namespace evidential_octomap
