// OctoMap's coordToKeyChecked casts coordinate / resolution to int before it checks the range:
// undefined behaviour for NaN, inf and points beyond the tree's extent (UBSan: "nan is outside
// the range of 'int'"). Every lookup of a caller's point goes through this instead.
#pragma once

#include <cmath>

#include <octomap/OcTreeBaseImpl.h>

namespace evidential_octomap {

// False (key untouched) for non-finite points and points outside the tree's key range, else
// the key of the voxel holding `point`. Works for any OctoMap tree (ours, ColorOcTree, OcTree).
template <class NODE, class INTERFACE>
bool safeCoordToKey(const octomap::OcTreeBaseImpl<NODE, INTERFACE>& tree,
                    const octomap::point3d& point, octomap::OcTreeKey* key) {
  // 16-bit keys: the tree spans resolution * 32768 on either side of the origin.
  const double extent = tree.getResolution() * 32768.0;
  for (unsigned i = 0; i < 3; ++i) {
    if (!(std::fabs(point(i)) < extent)) return false;
  }
  return tree.coordToKeyChecked(point, *key);
}

}  // namespace evidential_octomap
