// Map edits the node offers as services, kept out of MappingServer so they are tested without a
// roscore. (A core EvidentialOcTree::clearBox would be the better home.)
#pragma once

#include <cstdint>

#include <octomap/octomap_types.h>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// Clears [min, max] (map frame) as octomap_server's clear_bbx does: every leaf inside becomes
// free (log-odds at the clamping minimum) and loses its semantic evidence. Coarse leaves that
// straddle the border are split down to full depth first, so nothing outside the box changes.
// Returns the number of leaves cleared.
uint32_t clearBox(EvidentialOcTree* tree, const octomap::point3d& min, const octomap::point3d& max);

}  // namespace evidential_octomap
