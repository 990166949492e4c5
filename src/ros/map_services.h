// The work of the node's map services, request to response, without node state or a roscore:
// gtest-able, fuzzed (fuzz/fuzz_services.cpp), and the only place these requests touch the map.
// MappingServer locks the map, calls these and logs.
#pragma once

#include "evidential_octomap/ClearBbx.h"
#include "evidential_octomap/QueryMap.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/local_map.h"

namespace evidential_octomap {

// Per point: label and class name (the tree's), uncertainty, conflict, occupancy (-1: unknown)
// and beliefs, through the guarded
// EvidentialOcTree::nodeAt (NaN, inf and far-away points are unknown, never undefined).
// With `local` (whose resident map is `tree`), points on tiles on disk are answered from their
// tile (LocalMap::mapAt; throws std::runtime_error when a tile cannot be read).
void answerQuery(const EvidentialOcTree& tree, const QueryMap::Request& req,
                 QueryMap::Response* res, const LocalMap* local = nullptr);

// clearBox on the request's box. A refused box (non-finite or inverted) changes nothing:
// success false and the reason in message.
void clearBoxRequest(EvidentialOcTree* tree, const ClearBbx::Request& req, ClearBbx::Response* res);

}  // namespace evidential_octomap
