// Edits of a map the node offers as services (octomap_server's clear_bbx), in the core so the
// library, the node and the fuzz targets share one checked implementation.
#pragma once

#include <cstdint>
#include <string>

#include <octomap/octomap_types.h>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// "" when [min, max] is a box clearBox accepts: every coordinate finite and min <= max on each
// axis; else what is wrong. (A NaN corner used to clear the whole map: NaN compares false with
// every bound, so the box reached the map's edge.)
std::string boxProblem(const octomap::point3d& min, const octomap::point3d& max);

// Clears [min, max] (map frame) as octomap_server's clear_bbx does: every leaf inside becomes
// free (log-odds at the clamping minimum) and loses its semantic evidence. Coarse leaves that
// straddle the border are split down to full depth first, so nothing outside the box changes.
// A box beyond the map's extent is cut to it. Returns the number of leaves cleared; throws
// std::invalid_argument, changing nothing, for a box boxProblem() refuses.
uint32_t clearBox(EvidentialOcTree* tree, const octomap::point3d& min, const octomap::point3d& max);

}  // namespace evidential_octomap
