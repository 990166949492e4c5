#include "conversions.h"

#include <cstring>
#include <sstream>

#include "evidential_octomap/io.h"

namespace evidential_octomap {

using sensor_msgs::PointField;

std::string fromPointCloud2(const sensor_msgs::PointCloud2& msg, const CloudReadOptions& options,
                            SemanticCloud* out) {
  CloudLayout layout;
  for (const PointField& f : msg.fields)
    layout.fields.push_back({f.name, f.offset, f.datatype, f.count});
  layout.height = msg.height;
  layout.width = msg.width;
  layout.point_step = msg.point_step;
  layout.row_step = msg.row_step;
  layout.is_bigendian = msg.is_bigendian != 0;
  layout.data = msg.data.data();
  layout.size = msg.data.size();
  return readPointCloud2(layout, options, out);
}

VoxelView viewOfLeaf(const EvidentialOcTree& tree, const EvidentialOcTreeNode& node,
                     const octomap::point3d& center, double size, unsigned depth) {
  VoxelView v;
  v.center = center;
  v.size = size;
  v.depth = depth;
  if (node.hasSemantics() && tree.isNodeOccupied(node)) {
    const VoxelOpinion o = tree.opinion(&node);
    v.label = o.label;
    v.uncertainty = o.uncertainty;
    v.error_probability = tree.rule().errorProbability(o);
    v.conflict = o.conflict;
  }
  return v;
}

size_t keepHeightBand(const octomap::pose6d& T_F_S, const HeightBand& band, int num_classes,
                      SemanticCloud* scan) {
  if (band.unbounded()) return 0;
  octomap::Pointcloud kept;
  std::vector<float> evidence;
  const size_t n = scan->points_S.size();
  for (size_t i = 0; i < n; ++i) {
    const octomap::point3d& p = scan->points_S[i];
    if (!band.contains(T_F_S.transform(p).z())) continue;
    kept.push_back(p);
    evidence.insert(evidence.end(), scan->evidence.begin() + i * num_classes,
                    scan->evidence.begin() + (i + 1) * num_classes);
  }
  scan->points_S = kept;
  scan->evidence.swap(evidence);
  return n - kept.size();
}

EvidentialMap toEvidentialMap(const EvidentialOcTree& tree, const std::string& frame_id) {
  EvidentialMap msg;
  msg.header.frame_id = frame_id;
  msg.resolution = tree.getResolution();
  msg.num_classes = static_cast<uint16_t>(tree.numClasses());
  msg.class_names = tree.classNames();
  msg.fusion_rule = tree.rule().name();
  std::stringstream s;
  tree.write(s);
  const std::string bytes = s.str();
  msg.data.assign(bytes.begin(), bytes.end());
  return msg;
}

OccupancyMap toOccupancyMap(const EvidentialOcTree& tree, const std::string& frame_id) {
  OccupancyMap msg;
  msg.header.frame_id = frame_id;
  msg.resolution = tree.getResolution();
  std::stringstream s;
  writeBinaryOccupancy(tree, s);
  const std::string bytes = s.str();
  msg.data.assign(bytes.begin(), bytes.end());
  return msg;
}

float packRgb(const ClassTable::Rgb& rgb) {
  const uint32_t packed = (uint32_t(rgb[0]) << 16) | (uint32_t(rgb[1]) << 8) | uint32_t(rgb[2]);
  float f;
  std::memcpy(&f, &packed, sizeof(f));
  return f;
}

sensor_msgs::PointCloud2 toPointCloud2(const std::vector<VoxelView>& voxels,
                                       const ClassTable& classes, const std::string& frame_id) {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = frame_id;
  const char* names[8] = {"x",   "y",        "z", "label", "uncertainty", "rgb", "conflict",
                          "error_probability"};
  const uint8_t types[8] = {PointField::FLOAT32, PointField::FLOAT32, PointField::FLOAT32,
                            PointField::INT32,   PointField::FLOAT32, PointField::FLOAT32,
                            PointField::FLOAT32, PointField::FLOAT32};
  for (int i = 0; i < 8; ++i) {
    PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = types[i];
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.point_step = 32;
  msg.height = 1;
  msg.width = static_cast<uint32_t>(voxels.size());
  msg.row_step = msg.point_step * msg.width;
  msg.is_bigendian = false;
  msg.is_dense = true;
  msg.data.resize(size_t(msg.row_step));
  const ClassTable::Rgb grey{128, 128, 128};
  uint8_t* p = msg.data.data();
  for (const VoxelView& v : voxels) {
    const float xyz[3] = {v.center.x(), v.center.y(), v.center.z()};
    const int32_t label = v.label;
    const bool known = v.label >= 0 && v.label < int(classes.colors.size());
    const float rgb = packRgb(known ? classes.colors[v.label] : grey);
    std::memcpy(p, xyz, 12);
    std::memcpy(p + 12, &label, 4);
    std::memcpy(p + 16, &v.uncertainty, 4);
    std::memcpy(p + 20, &rgb, 4);
    std::memcpy(p + 24, &v.conflict, 4);
    std::memcpy(p + 28, &v.error_probability, 4);
    p += msg.point_step;
  }
  return msg;
}

}  // namespace evidential_octomap
