// Files: atomic .ot / .bt saves, a checked .ot loader, and export to OctoMap's ColorOcTree.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>

#include <octomap/ColorOcTree.h>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// Every file the project writes goes through this: `write` fills a temporary file of a unique
// name beside `path` (`<path>.tmp.<pid>.XXXXXX`, locked while it is written), which is fsynced
// and renamed over `path`, and the directory is fsynced. A reader sees the old file or the new
// one, never a torn one; concurrent writers of one path each produce a whole file and the last
// rename wins; a killed writer leaves its temporary behind, and the next write in the directory
// removes it (a temporary whose lock is free), never a live writer's. `write` returns false or
// leaves the stream failed to abort. Throws std::runtime_error naming the path and the reason.
void writeFileAtomically(const std::string& path, const std::function<bool(std::ostream&)>& write);
void writeFileAtomically(const std::string& path, const std::string& bytes);
// `to` becomes a hard link of `from` (the same bytes, no copy; a later atomic replace of `from`
// leaves `to` as it was), or a copy where links are impossible (another filesystem). Replaces
// an existing `to`. Throws std::runtime_error naming both paths and the reason.
void linkOrCopyFile(const std::string& from, const std::string& to);

// Writes `tree` as .ot (AbstractOcTree format, our type id) to `path`, atomically. Refuses
// (std::runtime_error) a tree whose parameters the reader would refuse (parameterProblem()).
void saveMap(const EvidentialOcTree& tree, const std::string& path);

// Occupancy-only OctoMap binary (.bt), loadable by plain octomap::OcTree; atomic like saveMap.
void saveBinaryOccupancy(const EvidentialOcTree& tree, const std::string& path);
// The same .bt stream: OctoMap's binary header with `id OcTree` (the data is exactly a plain
// OcTree's, so stock tools must not read or echo our own type id), then writeBinaryData.
bool writeBinaryOccupancy(const EvidentialOcTree& tree, std::ostream& s);

// An occupancy-only map from an OctoMap binary file (.bt: octomap_server's saved maps, or
// saveBinaryOccupancy's): every leaf's occupancy (the file's max-likelihood values), no evidence,
// in a tree of the file's resolution with `num_classes` and `config`, so mapping can go on from
// it. Throws std::runtime_error for a missing path or a file that is not an OctoMap .bt.
std::unique_ptr<EvidentialOcTree> loadBinaryOccupancy(const std::string& path, int num_classes,
                                                      const SemanticConfig& config);

// Reads an .ot written by saveMap: the safe way to load a map. Throws std::runtime_error for a
// missing path, anything but a regular file (FIFO, device, directory: nothing is read), a file
// larger than `max_bytes` (0: no limit), a file that is not an OctoMap file, a file of another
// tree type, or data that is corrupt, truncated or fails its checksum or invariants.
std::unique_ptr<EvidentialOcTree> loadMap(const std::string& path, uint64_t max_bytes = 0);
// The same checks on a stream holding .ot bytes (e.g. a map sent between processes); `path`
// names the source in error messages.
std::unique_ptr<EvidentialOcTree> loadMap(std::istream& in, const std::string& path);

// OctoMap's generic octomap::AbstractOcTree::read(path) never throws: for a corrupt data
// section it returns an empty tree (readError() says why), and for a header that says "size 0"
// it skips our data section (C, names, rule left at defaults). This one call tells: "" when
// `tree` is a completely read EvidentialOcTree, else why not (also for nullptr and other types).
std::string readProblem(const octomap::AbstractOcTree* tree);

// What a ColorOcTree's colours show (blue = certain ... red = uncertain for the last two):
//   kClass:       the argmax class, in the class table's colours;
//   kUncertainty: the default uncertainty, the probability that the label is wrong, 1 - max p
//                 (FusionRule::errorProbability), over [0, 1 - 1/C] (red: no class preferred);
//   kVacuity:     dempster's vacuity u over [0, 1]; sbki/ebs: the label's Dirichlet variance
//                 over [0, the map's largest].
enum class ColorMode { kClass, kUncertainty, kVacuity };
// "class", "uncertainty" or "vacuity" (the CLI's --mode, the node's ~full_map_colors, Python).
ColorMode colorModeFromName(const std::string& name);

// ColorOcTree with the same occupancy; semantic leaves coloured as `mode` says, leaves without
// evidence grey. The result opens in octovis and every stock OctoMap tool.
std::unique_ptr<octomap::ColorOcTree> toColorOcTree(const EvidentialOcTree& tree,
                                                    const ClassTable& classes, ColorMode mode);

// Colour map used for uncertainty everywhere (renders, markers, export): t in [0, 1].
ClassTable::Rgb uncertaintyColor(double t);

}  // namespace evidential_octomap
