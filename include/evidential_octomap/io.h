// Files: atomic .ot / .bt saves, a checked .ot loader, and export to OctoMap's ColorOcTree.
#pragma once

#include <iosfwd>
#include <memory>
#include <string>

#include <octomap/ColorOcTree.h>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// Writes `tree` as .ot (AbstractOcTree format, our type id) to `path`: a temporary file in the
// same directory is written, flushed and renamed over `path`, so a reader sees the old file or
// the new one, never a torn one. Throws std::runtime_error naming the path and the reason.
void saveMap(const EvidentialOcTree& tree, const std::string& path);

// Occupancy-only OctoMap binary (.bt), loadable by plain octomap::OcTree; atomic like saveMap.
void saveBinaryOccupancy(const EvidentialOcTree& tree, const std::string& path);
// The same .bt stream: OctoMap's binary header with `id OcTree` (the data is exactly a plain
// OcTree's, so stock tools must not read or echo our own type id), then writeBinaryData.
bool writeBinaryOccupancy(const EvidentialOcTree& tree, std::ostream& s);

// Reads an .ot written by saveMap. Throws std::runtime_error for a missing path, a file that is
// not an OctoMap file, a file of another tree type, or corrupt/truncated data.
std::unique_ptr<EvidentialOcTree> loadMap(const std::string& path);
// The same checks on a stream holding .ot bytes (e.g. a map sent between processes); `path`
// names the source in error messages.
std::unique_ptr<EvidentialOcTree> loadMap(std::istream& in, const std::string& path);

enum class ColorMode { kClass, kUncertainty };

// ColorOcTree with the same occupancy; occupied semantic leaves coloured by argmax class
// (colours from `classes`) or by uncertainty (blue = certain ... red = uncertain). Leaves without
// evidence are grey. The result opens in octovis and every stock OctoMap tool.
std::unique_ptr<octomap::ColorOcTree> toColorOcTree(const EvidentialOcTree& tree,
                                                    const ClassTable& classes, ColorMode mode);

// Colour map used for uncertainty everywhere (renders, markers, export): t in [0, 1].
ClassTable::Rgb uncertaintyColor(double t);

}  // namespace evidential_octomap
