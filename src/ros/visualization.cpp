#include "visualization.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "evidential_octomap/io.h"

namespace evidential_octomap {
namespace {

std_msgs::ColorRGBA toColor(const ClassTable::Rgb& rgb) {
  std_msgs::ColorRGBA c;
  c.r = rgb[0] / 255.f;
  c.g = rgb[1] / 255.f;
  c.b = rgb[2] / 255.f;
  c.a = 1.f;
  return c;
}

// One CUBE_LIST per depth 0..tree_depth; colour_of(voxel) picks each cube's colour.
template <typename ColorOf>
visualization_msgs::MarkerArray cubesByDepth(const std::vector<VoxelView>& voxels,
                                             const std::string& ns, const std::string& frame_id,
                                             unsigned tree_depth, ColorOf colour_of) {
  visualization_msgs::MarkerArray array;
  array.markers.resize(tree_depth + 1);
  for (unsigned d = 0; d <= tree_depth; ++d) {
    visualization_msgs::Marker& m = array.markers[d];
    m.header.frame_id = frame_id;
    m.ns = ns;
    m.id = static_cast<int>(d);
    m.type = visualization_msgs::Marker::CUBE_LIST;
    m.pose.orientation.w = 1.0;
    m.color.a = 1.f;
  }
  for (const VoxelView& v : voxels) {
    if (v.depth > tree_depth) continue;
    visualization_msgs::Marker& m = array.markers[v.depth];
    m.scale.x = m.scale.y = m.scale.z = v.size;
    geometry_msgs::Point p;
    p.x = v.center.x();
    p.y = v.center.y();
    p.z = v.center.z();
    m.points.push_back(p);
    m.colors.push_back(colour_of(v));
  }
  for (visualization_msgs::Marker& m : array.markers)
    m.action =
        m.points.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
  return array;
}

}  // namespace

visualization_msgs::MarkerArray semanticMarkers(const std::vector<VoxelView>& voxels,
                                                const ClassTable& classes,
                                                const std::string& frame_id, unsigned tree_depth) {
  const std_msgs::ColorRGBA grey = toColor({128, 128, 128});
  std::vector<std_msgs::ColorRGBA> palette;
  for (const auto& rgb : classes.colors) palette.push_back(toColor(rgb));
  return cubesByDepth(voxels, "semantic", frame_id, tree_depth, [&](const VoxelView& v) {
    return v.label >= 0 && v.label < int(palette.size()) ? palette[v.label] : grey;
  });
}

UncertaintyView uncertaintyViewFromName(const std::string& name) {
  if (name == "error_probability") return UncertaintyView::kErrorProbability;
  if (name == "vacuity") return UncertaintyView::kVacuity;
  throw std::invalid_argument("~uncertainty_view must be 'error_probability' or 'vacuity', not '" +
                              name + "'");
}

float shownUncertainty(const VoxelView& voxel, UncertaintyView view) {
  return view == UncertaintyView::kVacuity ? voxel.uncertainty : voxel.error_probability;
}

UncertaintyRange resolveRange(const std::vector<VoxelView>& voxels, const UncertaintyRange& range,
                              UncertaintyView view) {
  if (!range.automatic || voxels.empty()) return {false, range.min, range.max};
  // Fitted to the map's distribution of the value: its 5th to 95th percentile spans the colour
  // map (most voxels sit near the read-out floor; min..max would give them all one colour).
  std::vector<float> u;
  u.reserve(voxels.size());
  for (const VoxelView& v : voxels) u.push_back(shownUncertainty(v, view));
  auto percentile = [&](double q) {
    auto nth = u.begin() + std::lround(q * double(u.size() - 1));
    std::nth_element(u.begin(), nth, u.end());
    return double(*nth);
  };
  return {true, percentile(0.05), percentile(0.95)};
}

namespace {
// Cubes coloured by uncertaintyColor of value_of(voxel) scaled from [lo, hi] to [0, 1].
template <typename ValueOf>
visualization_msgs::MarkerArray rampMarkers(const std::vector<VoxelView>& voxels,
                                            const std::string& ns, double lo, double hi,
                                            const std::string& frame_id, unsigned tree_depth,
                                            ValueOf value_of) {
  const double span = hi > lo ? hi - lo : 1.0;
  return cubesByDepth(voxels, ns, frame_id, tree_depth, [&](const VoxelView& v) {
    const double t = std::min(1.0, std::max(0.0, (value_of(v) - lo) / span));
    return toColor(uncertaintyColor(t));
  });
}
}  // namespace

visualization_msgs::MarkerArray uncertaintyMarkers(const std::vector<VoxelView>& voxels,
                                                   const UncertaintyRange& range,
                                                   UncertaintyView view,
                                                   const std::string& frame_id,
                                                   unsigned tree_depth) {
  const UncertaintyRange r = resolveRange(voxels, range, view);
  return rampMarkers(voxels, "uncertainty", r.min, r.max, frame_id, tree_depth,
                     [view](const VoxelView& v) { return shownUncertainty(v, view); });
}

visualization_msgs::MarkerArray conflictMarkers(const std::vector<VoxelView>& voxels,
                                                const std::string& frame_id, unsigned tree_depth) {
  return rampMarkers(voxels, "conflict", 0.0, 1.0, frame_id, tree_depth,
                     [](const VoxelView& v) { return v.conflict; });
}

visualization_msgs::MarkerArray freeMarkers(const std::vector<VoxelView>& voxels,
                                            const std::string& frame_id, unsigned tree_depth) {
  // octomap_server's colour of free space: translucent green.
  std_msgs::ColorRGBA green;
  green.g = 1.f;
  green.a = 0.25f;
  auto array =
      cubesByDepth(voxels, "free", frame_id, tree_depth, [&](const VoxelView&) { return green; });
  for (auto& m : array.markers) m.color = green;
  return array;
}

}  // namespace evidential_octomap
