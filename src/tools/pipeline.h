// The mapping run shared by `map`, `compare` and the end-to-end tests: load scans, derive their
// evidence, insert them into an EvidentialOcTree (timed), build queries, evaluate.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evidence/evidence_sources.h"
#include "synthetic.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/evaluation/metrics.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap::tools {

// Which scans are mapped and which are queried.
//   reconstruction: map scans 0..n-1, query the same scans;
//   held-out:       map the first half (0..n/2-1), query the second half (n/2..n-1).
struct Protocol {
  std::string name;
  std::vector<size_t> map_scans;
  std::vector<size_t> query_scans;
};
// Replaces every scan's predictions by its GT corrupted with `noise` (SYNTHETIC predictions);
// returns the description to print beside the results.
std::string useSyntheticPredictions(std::vector<Scan>* scans, const ClassTable& classes,
                                    const NoiseModel& noise);

Protocol makeProtocol(const std::string& name, size_t num_scans);  // throws std::invalid_argument

// Loads scans 0..n-1 of the dataset (n = min(limit, size), limit 0 = all), with a progress bar.
std::vector<Scan> loadScans(const Dataset& dataset, size_t limit, bool progress);

// GT-labelled points (gt != ignore_class) of `which` scans in the world frame, with the input's
// prediction of each (-1 when the scan has none). With `evidence` (indexed like `scans`) and
// `query_evidence`, the C evidence values of every query are appended there, in query order.
std::vector<Query> buildQueries(const std::vector<Scan>& scans, const std::vector<size_t>& which,
                                int ignore_class,
                                const std::vector<std::vector<float>>* evidence = nullptr,
                                std::vector<float>* query_evidence = nullptr);

// Keys of the voxels that hold a ray end point of scans `which` (for occupiedWithoutEndpoint).
std::vector<octomap::OcTreeKey> endpointKeys(const std::vector<Scan>& scans,
                                             const std::vector<size_t>& which, double resolution);

// Evidence of each scan in `which` and `also` (indexed like `scans`; other entries stay empty).
// Calibrated sources are fitted on the `which` scans only (leave-one-scan-out for those), so
// the query scans of the held-out protocol (`also`) never calibrate anything.
std::vector<std::vector<float>> deriveEvidenceFor(const std::vector<Scan>& scans,
                                                  const std::vector<size_t>& which,
                                                  const EvidenceOptions& options,
                                                  const ClassTable& classes,
                                                  const std::vector<size_t>& also = {});

struct MapRun {
  std::unique_ptr<EvidentialOcTree> tree;
  std::vector<double> ms_per_scan;  // insertSemanticScan wall time, per mapped scan
  InsertStats total;                // summed over scans (uncertainty_threshold: last scan)
  size_t scans_mapped = 0;
  double ms_median() const;
  double ms_mean() const;
};

// Every `every` scans the map so far is written to `path` (saveMap: atomic, so a killed run
// leaves the last complete autosave); every = 0: never.
struct Autosave {
  std::string path;
  size_t every = 0;
};

// A local map (local_map.h): radius 0 keeps the whole map in memory.
struct LocalMapOptions {
  double radius = 0.0;
  std::string tile_directory;
};

// Inserts scans `which` (in order) with their evidence into a new tree. With a local map, the
// run's tree is the global map at the end (the resident region merged with the tiles).
MapRun runMapping(const std::vector<Scan>& scans, const std::vector<size_t>& which,
                  const std::vector<std::vector<float>>& evidence, const ClassTable& classes,
                  const SemanticConfig& config, double resolution, bool progress,
                  const std::string& label = "mapping", const Autosave& autosave = {},
                  const LocalMapOptions& local_map = {});

}  // namespace evidential_octomap::tools
