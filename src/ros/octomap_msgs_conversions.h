// EvidentialOcTree -> octomap_msgs/Octomap, as octomap_server publishes its maps (built only when
// octomap_msgs is found). Free functions, testable without a roscore; the result is read back
// by octomap_msgs' own conversions.h (msgToMap).
#pragma once

#include <octomap_msgs/Octomap.h>

#include <string>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"

namespace evidential_octomap {

// octomap_binary: occupancy as a plain OcTree (id "OcTree", binary), what every octomap_msgs
// user (MoveIt, the octomap rviz plugins, planners) reads with binaryMsgToMap.
octomap_msgs::Octomap toOctomapBinary(const EvidentialOcTree& tree, const std::string& frame_id);

// octomap_full: the semantic map as a ColorOcTree (id "ColorOcTree", full), class or uncertainty
// colours, so stock displays show it.
octomap_msgs::Octomap toOctomapFull(const EvidentialOcTree& tree, const ClassTable& classes,
                                    ColorMode mode, const std::string& frame_id);

// The EvidentialOcTree itself (id "EvidentialOcTree", full): fullMsgToMap in a program that links
// this library returns an EvidentialOcTree.
octomap_msgs::Octomap toOctomapEvidential(const EvidentialOcTree& tree,
                                          const std::string& frame_id);

}  // namespace evidential_octomap
