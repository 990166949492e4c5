// Ghosts of movers on SYNTHETIC street scenes (moving_scene.h), per settings row and mover,
// measured `lag` scans after the mover left, beside plain OctoMap fed the same rays:
//   freed        swept voxels (centre inside the mover's box at some scan, above the road's
//                voxel layer) that rays have cleared since the mover last covered them (plain
//                OctoMap's log-odds lower than then): what it freed and the sensor saw empty;
//   ghost_share  share of them whose answer (EvidentialOcTree::answer, as a query sees it) is
//                the mover's class;
//   occupied_share / plain_occupied_share: share of them occupied in this map / in plain's;
//   own_ghost_share the same from the voxel's own evidence only (EvidentialOcTree::query);
//   free_ghost_share share of the freed voxels that plain OctoMap holds free and whose answer
//                is the mover's class (a voxel still occupied keeps its class by design);
//   road_share   share of the road surface under its path (road-layer voxels inside its
//                footprint at some scan that plain OctoMap holds occupied) that answer `road`;
//   road_taken_share share of the road-layer voxels under its path that plain OctoMap knows
//                (free ones, which grazing rays cross, included) that answer the mover's class.
// Usage: moving_street [--lag N] ROW...   ROW = LABEL:defaults|FILE.yaml[:key=value,...]
// Prints one JSON line per (case, row, mover).
#include <octomap/OcTree.h>

#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "ghost_counts.h"
#include "moving_scene.h"
#include "plain_octomap.h"
#include "settings_rows.h"

using evidential_octomap::EvidentialOcTree;
using evidential_octomap::SemanticConfig;
namespace ms = moving_scene;

namespace {

constexpr double kResolution = 0.2;

using Row = evbench::SettingsRow;

using Key = std::tuple<int, int, int>;

// The voxels a mover swept (above the road layer) and the road voxels under its path; for each
// swept voxel, plain OctoMap's log-odds after the last scan the mover covered it.
struct Footprint {
  std::set<Key> swept, road;
  std::map<Key, float> left;
};

// Adds the voxels of the mover's box at `scan` to f; returns the swept ones.
std::vector<Key> addBox(const ms::Mover& m, int scan, const EvidentialOcTree& tree, Footprint* f) {
  std::vector<Key> swept;
  const double r = kResolution;
  const ms::Box b = m.at(scan);
  for (double x = b.min.x() - r; x <= b.max.x() + r; x += r)
    for (double y = b.min.y() - r; y <= b.max.y() + r; y += r)
      for (double z = ms::kRoadZ; z <= b.max.z() + r; z += r) {
        const octomap::OcTreeKey k = tree.coordToKey(x, y, z);
        octomap::point3d c = tree.keyToCoord(k);
        const bool road_layer = std::fabs(c.z() - ms::kRoadZ) < 0.5 * r;
        if (road_layer) c.z() = b.min.z() + 0.01f;  // the footprint
        if (!b.contains(c)) continue;
        const Key key{k[0], k[1], k[2]};
        if (road_layer) {
          f->road.insert(key);
        } else {
          f->swept.insert(key);
          swept.push_back(key);
        }
      }
  return swept;
}

struct Shares : evbench::GhostCounts {
  size_t road = 0, road_kept = 0, road_known = 0, road_taken = 0;
};

Shares measure(const EvidentialOcTree& tree, const octomap::OcTree& plain, const Footprint& f,
               int label) {
  Shares s;
  for (const auto& [key, then] : f.left) {
    const auto& [x, y, z] = key;
    evbench::countIfFreed(tree, plain, octomap::OcTreeKey(x, y, z), then, label, &s);
  }
  for (const auto& [x, y, z] : f.road) {
    const octomap::OcTreeKey k(x, y, z);
    const octomap::OcTreeNode* p = plain.search(k);
    if (!p) continue;
    ++s.road_known;
    s.road_taken += tree.answer(k).label == label;
    if (!plain.isNodeOccupied(p)) continue;
    ++s.road;
    s.road_kept += tree.answer(k).label == ms::kRoad;
  }
  return s;
}

using evbench::share;

void print(const ms::Case& c, const std::string& row, const ms::Mover& m, int lag,
           const Shares& s) {
  std::cout << "{\"case\":\"" << c.name << "\",\"settings\":\"" << row << "\",\"mover\":\""
            << m.name << "\",\"class\":\"" << ms::className(m.label) << "\",\"lag\":" << lag
            << ",\"freed\":" << s.freed << ",\"ghost_share\":" << share(s.ghosts, s.freed)
            << ",\"own_ghost_share\":" << share(s.own_ghosts, s.freed)
            << ",\"free_ghost_share\":" << share(s.free_ghosts, s.freed)
            << ",\"occupied_share\":" << share(s.occupied, s.freed)
            << ",\"plain_occupied_share\":" << share(s.plain_occupied, s.freed)
            << ",\"road\":" << s.road << ",\"road_share\":" << share(s.road_kept, s.road)
            << ",\"road_taken_share\":" << share(s.road_taken, s.road_known) << "}" << std::endl;
}

// Every row's map and plain OctoMap's, fed the same scans in turn.
void runCase(const ms::Case& c, const std::vector<Row>& rows, int lag) {
  std::vector<bool> ground(ms::kClasses, false), movable(ms::kClasses, false);
  ground[ms::kRoad] = true;
  movable[ms::kPerson] = movable[ms::kCar] = true;  // as the shipped class tables mark them
  std::vector<EvidentialOcTree> trees;
  trees.reserve(rows.size());
  for (const Row& row : rows) {
    trees.emplace_back(kResolution, ms::kClasses, row.config);
    trees.back().setGroundClasses(ground);
    trees.back().setMovableClasses(movable);
  }
  std::vector<double> cpu_ms(rows.size(), 0.0);
  octomap::OcTree plain(kResolution);
  ms::Sensor sensor;
  std::vector<Footprint> feet(c.movers.size());
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (int scan = 0; scan < c.scans; ++scan) {
    sensor.scan(c, scan, &points, &evidence);
    for (size_t r = 0; r < rows.size(); ++r) {
      const auto stats = trees[r].insertSemanticScan(points, evidence, sensor.origin);
      cpu_ms[r] += stats.cpu_ms_occupancy + stats.cpu_ms_kernel + stats.cpu_ms_update;
    }
    evbench::plainInsert(plain, points, sensor.origin, -1.0, true);
    for (size_t i = 0; i < c.movers.size(); ++i) {
      if (c.movers[i].present(scan)) {
        for (const Key& key : addBox(c.movers[i], scan, trees[0], &feet[i])) {
          const auto& [x, y, z] = key;
          const octomap::OcTreeNode* p = plain.search(octomap::OcTreeKey(x, y, z));
          feet[i].left[key] = p ? p->getLogOdds() : std::numeric_limits<float>::infinity();
        }
      }
      if (scan != c.movers[i].last + lag) continue;
      for (size_t r = 0; r < rows.size(); ++r)
        print(c, rows[r].label, c.movers[i], lag, measure(trees[r], plain, feet[i], c.movers[i].label));
    }
  }
  for (size_t r = 0; r < rows.size(); ++r)
    std::cerr << c.name << " / " << rows[r].label << ": " << cpu_ms[r] << " ms insert CPU\n";
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int lag = 10;
    std::vector<Row> rows;
    std::string only;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--lag" && i + 1 < argc) {
        lag = std::stoi(argv[++i]);
      } else if (a == "--case" && i + 1 < argc) {
        only = argv[++i];
      } else {
        rows.push_back(evbench::parseSettingsRow(a));
      }
    }
    if (rows.empty() || lag < 1 || lag > 20) {
      std::cerr << "usage: moving_street [--lag 1..20] [--case NAME] "
                   "LABEL:defaults|FILE.yaml[:key=value,...]...\n";
      return 2;
    }
    for (const ms::Case& c : ms::cases())
      if (only.empty() || c.name == only)
        runCase(c, rows, lag);
  } catch (const std::exception& e) {
    std::cerr << "moving_street: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
