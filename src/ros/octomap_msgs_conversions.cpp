#include "octomap_msgs_conversions.h"

#include <sstream>

namespace evidential_octomap {
namespace {

octomap_msgs::Octomap message(const std::string& id, bool binary, double resolution,
                              const std::string& frame_id, const std::string& bytes) {
  octomap_msgs::Octomap msg;
  msg.header.frame_id = frame_id;
  msg.id = id;
  msg.binary = binary;
  msg.resolution = resolution;
  msg.data.assign(bytes.begin(), bytes.end());
  return msg;
}

}  // namespace

octomap_msgs::Octomap toOctomapBinary(const EvidentialOcTree& tree, const std::string& frame_id) {
  // The binary stream is OccupancyOcTreeBase's, the same for every occupancy tree type; the id
  // says which type to create, and every reader creates a plain OcTree for "OcTree".
  std::stringstream s;
  tree.writeBinaryData(s);
  return message("OcTree", true, tree.getResolution(), frame_id, s.str());
}

octomap_msgs::Octomap toOctomapFull(const EvidentialOcTree& tree, const ClassTable& classes,
                                    ColorMode mode, const std::string& frame_id) {
  const std::unique_ptr<octomap::ColorOcTree> color = toColorOcTree(tree, classes, mode);
  std::stringstream s;
  color->writeData(s);
  return message(color->getTreeType(), false, tree.getResolution(), frame_id, s.str());
}

octomap_msgs::Octomap toOctomapEvidential(const EvidentialOcTree& tree,
                                          const std::string& frame_id) {
  std::stringstream s;
  tree.writeData(s);
  return message(tree.getTreeType(), false, tree.getResolution(), frame_id, s.str());
}

}  // namespace evidential_octomap
