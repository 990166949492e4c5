// The autosave of a map kept as a LocalMap, without building the whole map: a directory
// <base>/snapshot_<n>/ holding resident.ot (the tree in memory) and a hard link of every tile
// on disk, all of one moment. Tiles on disk never change (a tile that leaves again is a new
// file renamed over the old name), so linking them is a consistent copy that costs no copy. A
// snapshot is made complete as a staging directory and renamed into place: every snapshot_<n>
// is whole, the highest n is the newest, and a writer killed at any moment leaves the previous
// snapshot readable.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/local_map.h"

namespace evidential_octomap {

// Step 1, under the map lock (cheap: links only): a fresh staging directory under `base` with
// the tiles on disk linked into it. Returns its path. Throws std::runtime_error.
std::string stageLocalMapSnapshot(const LocalMap& map, const std::string& base);
// Step 2, outside the lock: writes `resident_bytes` (the tree's .ot bytes, taken under the same
// lock) as resident.ot, renames the staging directory to the next snapshot_<n> and removes the
// older snapshots. Returns the snapshot's path. Throws std::runtime_error (a full disk, ...),
// removing the staging directory and leaving the previous snapshot as it was.
std::string commitLocalMapSnapshot(const std::string& staging, const std::string& resident_bytes,
                                   const std::string& base);

struct LocalMapSnapshot {
  std::string directory;           // "" when `base` holds none
  std::string resident;            // <directory>/resident.ot
  std::vector<std::string> tiles;  // the tile files in it
};
// The newest snapshot under `base`; removes staging directories that killed writers left.
LocalMapSnapshot newestLocalMapSnapshot(const std::string& base);

}  // namespace evidential_octomap
