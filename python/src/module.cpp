// evidential_octomap._core: the Python module over the core library (no ROS).
// C++ exceptions arrive in Python with their message: std::invalid_argument as ValueError,
// std::out_of_range as IndexError, std::runtime_error (file errors) as RuntimeError.
#include "bindings.h"

namespace evidential_octomap::python {

Array<bool> toNumpyBool(std::vector<uint8_t>&& flags) {
  auto* owner = new std::vector<uint8_t>(std::move(flags));
  nb::capsule free_when_done(
      owner, [](void* p) noexcept { delete static_cast<std::vector<uint8_t>*>(p); });
  const size_t shape[1] = {owner->size()};
  return Array<bool>(reinterpret_cast<bool*>(owner->data()), 1, shape, free_when_done);
}

octomap::Pointcloud toPointcloud(const PointsIn& points) {
  octomap::Pointcloud cloud;
  cloud.reserve(points.shape(0));
  const auto view = points.view();
  for (size_t i = 0; i < points.shape(0); ++i) cloud.push_back(view(i, 0), view(i, 1), view(i, 2));
  return cloud;
}

Array<float> cloudArray(const octomap::Pointcloud& cloud) {
  std::vector<float> xyz;
  xyz.reserve(cloud.size() * 3);
  for (const auto& p : cloud) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
  return toNumpy(std::move(xyz), {cloud.size(), 3});
}

octomap::Pointcloud toPointcloud(const PointsIn& points, const PoseIn& T_W_S) {
  octomap::Pointcloud cloud;
  cloud.reserve(points.shape(0));
  const auto p = points.view();
  const auto T = T_W_S.view();
  for (size_t i = 0; i < points.shape(0); ++i) {
    double world[3];
    for (int r = 0; r < 3; ++r) {
      world[r] = T(r, 0) * p(i, 0) + T(r, 1) * p(i, 1) + T(r, 2) * p(i, 2) + T(r, 3);
    }
    cloud.push_back(float(world[0]), float(world[1]), float(world[2]));
  }
  return cloud;
}

}  // namespace evidential_octomap::python

NB_MODULE(_core, m) {
  using namespace evidential_octomap::python;
  m.doc() = "Uncertainty-aware semantic OctoMap: Dempster-Shafer fusion of per-point evidence.";
  bindClassTable(m);
  bindConfig(m);
  bindTree(m);
  bindLocalMap(m);
  bindDataset(m);
  bindMetrics(m);
  bindConversions(m);
  bindSettings(m);
#ifdef EVIDENTIAL_OCTOMAP_PYTHON_RENDER
  bindRender(m);
#endif
}
