// The node's account of its input (clouds received, inserted, dropped and why; insert time;
// queue; map size) as the ~status message and as a diagnostic_msgs status for /diagnostics
// (rqt_robot_monitor), so a node that falls behind says so.
#pragma once

#include <diagnostic_msgs/DiagnosticStatus.h>

#include <cstdint>
#include <string>

#include "evidential_octomap/MappingStatus.h"

namespace evidential_octomap {

inline uint64_t cloudsDropped(const MappingStatus& s) {
  return s.clouds_dropped_queue + s.clouds_dropped_invalid + s.clouds_dropped_tf;
}

// One diagnostic for `now`: WARN when clouds were dropped since `before` (the status of the
// previous report), else OK; every counter as a key/value pair.
diagnostic_msgs::DiagnosticStatus toDiagnosticStatus(const MappingStatus& now,
                                                     const MappingStatus& before,
                                                     const std::string& node_name);

}  // namespace evidential_octomap
