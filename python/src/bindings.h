// Shared by the binding files: one bind function per area, and the numpy conversions they use.
// Arrays cross the boundary as whole buffers (no per-point Python work); inputs of another dtype
// or layout are converted by nanobind (one copy), outputs are new numpy arrays owned by Python.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <octomap/Pointcloud.h>

#include <array>
#include <cstddef>
#include <functional>
#include <initializer_list>
#include <memory>
#include <optional>
#include <vector>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap::python {

namespace nb = nanobind;

using PointsIn = nb::ndarray<const float, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using MatrixIn = nb::ndarray<const float, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using LabelsIn = nb::ndarray<const int32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using PoseIn = nb::ndarray<const double, nb::shape<4, 4>, nb::c_contig, nb::device::cpu>;

template <typename T>
using Array = nb::ndarray<nb::numpy, T>;
// Policy of properties that return arrays: the numpy array is shared, never copied (nanobind's
// default for properties, reference_internal, refuses arrays that own their memory).
constexpr auto kShared = nb::rv_policy::automatic;

// A numpy array that takes ownership of `data` (shape must match its size).
template <typename T>
Array<T> toNumpy(std::vector<T>&& data, std::initializer_list<size_t> shape) {
  auto* owner = new std::vector<T>(std::move(data));
  nb::capsule free_when_done(owner,
                             [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
  return Array<T>(owner->data(), shape.size(), shape.begin(), free_when_done);
}
// numpy bool array from 0/1 bytes (std::vector<bool> has no buffer).
Array<bool> toNumpyBool(std::vector<uint8_t>&& flags);

// (N, 3) points as an OctoMap cloud; with a pose, transformed by it in double precision.
octomap::Pointcloud toPointcloud(const PointsIn& points);
octomap::Pointcloud toPointcloud(const PointsIn& points, const PoseIn& T_W_S);
// An OctoMap cloud as (N, 3) float32.
Array<float> cloudArray(const octomap::Pointcloud& cloud);

// EvidentialOcTree.insert_scan: exactly one of origin (points in the map frame) and pose (4x4
// sensor-to-map, points in the sensor frame); the GIL is released while the scan is inserted.
InsertStats insertScan(EvidentialOcTree& tree, const PointsIn& points, const MatrixIn& evidence,
                       std::optional<std::array<double, 3>> origin, std::optional<PoseIn> pose,
                       EvidentialOcTree* unobserved);

// What query() returns for N points.
struct QueryResult {
  Array<int32_t> labels;     // (N,) argmax class, -1 without semantic evidence
  Array<float> belief;       // (N, C)
  Array<float> uncertainty;  // (N,)
  Array<float> conflict;     // (N,)
  Array<float> error_probability;  // (N,) 1 - max_c p_c (FusionRule::errorProbability)
  Array<bool> occupied;      // (N,) the voxel is known and occupied
  Array<bool> known;         // (N,) the voxel exists in the map (observed)
};

// The map that answers a point (LocalMap::mapAt, TiledMap::mapAt).
using MapAt = std::function<const EvidentialOcTree&(const octomap::point3d&)>;
// EvidentialOcTree.query; with `map_at` (maps of `tree`'s class count), each point is answered
// from the map it gives, one point after another (tiles read from disk are not thread-safe).
QueryResult query(const EvidentialOcTree& tree, const PointsIn& points, const MapAt& map_at = {});

void bindClassTable(nb::module_& m);
void bindLocalMap(nb::module_& m);
void bindConfig(nb::module_& m);
void bindTree(nb::module_& m);
void bindDataset(nb::module_& m);
void bindMetrics(nb::module_& m);
void bindConversions(nb::module_& m);
void bindSettings(nb::module_& m);
#ifdef EVIDENTIAL_OCTOMAP_PYTHON_RENDER
void bindRender(nb::module_& m);
#endif

}  // namespace evidential_octomap::python
