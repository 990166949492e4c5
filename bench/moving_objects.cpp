// Moving objects on a generated sequence (SYNTHETIC, `evidential_octomap generate`): maps it once
// per settings row (the class table's movable and ground classes), beside plain OctoMap fed the
// same rays, and reports at the end, per mover, over the voxels it swept (centre inside its box
// at some scan) and left at least `lag` scans before, what moving_street.cpp reports for its
// street scenes:
//   freed        those that rays have cleared since it left them (plain OctoMap's log-odds
//                lower than after the last scan its box covered them);
//   ghost_share  share of them whose answer (EvidentialOcTree::answer, as a query sees it) is
//                the mover's class; free_ghost_share: of them, those plain OctoMap holds free;
//   occupied_share / plain_occupied_share: share of them occupied in this map / in plain's;
// and a DynamicMap_Benchmark-style static / dynamic accuracy over every point of the sequence:
//   static accuracy  = share of static points whose voxel is occupied and answers their class;
//   dynamic accuracy = share of mover points whose voxel no longer answers the mover's class.
// Usage: moving_objects [--lag N] DATASET ROW...   ROW = LABEL:defaults|FILE.yaml[:key=value,...]
// Prints one JSON line per row.
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evidential_octree.h"
#include "ghost_counts.h"
#include "plain_octomap.h"
#include "settings_rows.h"

using evidential_octomap::EvidentialOcTree;
using evidential_octomap::Dataset;
using evidential_octomap::readLabelFile;
using evidential_octomap::Scan;

namespace {

struct Box {
  double x, y, z, yaw, length, width, height;
};

using Key = std::tuple<int, int, int>;

struct Mover {
  std::map<int, Box> boxes;  // scan -> its box then
  // Each voxel it swept: the last scan its box covered it, and plain log-odds after that scan.
  std::map<Key, std::pair<int, float>> covered;
  std::map<int, size_t> classes;  // GT class of its points -> count
};

std::map<int, Mover> readMovers(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::map<int, Mover> movers;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string f[11];
    for (auto& field : f) std::getline(s, field, ',');
    Mover& m = movers[std::stoi(f[1])];
    m.boxes[std::stoi(f[0])] = {std::stod(f[3]), std::stod(f[4]), std::stod(f[5]),
                                std::stod(f[6]), std::stod(f[7]), std::stod(f[8]),
                                std::stod(f[9])};
  }
  return movers;
}

// Voxels whose centre lies in the box.
std::vector<Key> boxVoxels(const Box& b, const octomap::OcTree& tree) {
  std::vector<Key> keys;
  const double r = tree.getResolution();
  const double reach = 0.5 * std::hypot(b.length, b.width) + r;
  for (double x = b.x - reach; x <= b.x + reach; x += r)
    for (double y = b.y - reach; y <= b.y + reach; y += r)
      for (double z = b.z - 0.5 * b.height; z <= b.z + 0.5 * b.height; z += r) {
        const octomap::OcTreeKey k = tree.coordToKey(x, y, z);
        const octomap::point3d c = tree.keyToCoord(k);
        const double dx = c.x() - b.x, dy = c.y() - b.y;
        const double along = std::cos(b.yaw) * dx + std::sin(b.yaw) * dy;
        const double across = -std::sin(b.yaw) * dx + std::cos(b.yaw) * dy;
        if (std::fabs(along) <= 0.5 * b.length && std::fabs(across) <= 0.5 * b.width &&
            std::fabs(c.z() - b.z) <= 0.5 * b.height)
          keys.push_back({k[0], k[1], k[2]});
      }
  return keys;
}

int majorityClass(const Mover& m) {
  int best = -1;
  size_t most = 0;
  for (const auto& [c, n] : m.classes)
    if (n > most) best = c, most = n;
  return best;
}

struct Point {
  octomap::point3d p;
  int gt;
  int mover;  // instance, 0 static
};

using Shares = evbench::GhostCounts;
using evbench::share;

// The voxels the mover left at least `lag` scans before scan `now`.
Shares measure(const EvidentialOcTree& tree, const octomap::OcTree& plain, const Mover& m,
               int cls, int now, int lag) {
  Shares s;
  for (const auto& [key, last] : m.covered) {
    const auto& [scan, then] = last;
    if (scan + lag > now) continue;
    const auto& [x, y, z] = key;
    evbench::countIfFreed(tree, plain, octomap::OcTreeKey(x, y, z), then, cls, &s);
  }
  return s;
}

// The points of the sequence with their class and mover, and each mover's classes.
std::vector<Point> collectPoints(const Dataset& data, std::map<int, Mover>& movers) {
  std::vector<Point> points;
  for (size_t i = 0; i < data.size(); ++i) {
    const Scan scan = data.load(i);
    const auto raw = readLabelFile(data.path() + "/labels/" + scan.name + ".label");
    for (size_t j = 0; j < scan.size(); ++j) {
      const Eigen::Vector3f w = scan.pointW(j);
      const int instance = int(raw[j] >> 16);
      points.push_back({octomap::point3d(w.x(), w.y(), w.z()), scan.gt[j], instance});
      if (instance) ++movers[instance].classes[scan.gt[j]];
    }
  }
  return points;
}

void printRow(const std::string& label, const EvidentialOcTree& tree,
              const std::vector<Point>& points, std::map<int, Mover>& movers,
              const std::vector<std::pair<int, Shares>>& per_mover, int lag) {
  size_t st = 0, st_ok = 0, dy = 0, dy_ok = 0;
  for (const Point& p : points) {
    const auto* node = tree.nodeAt(p.p);
    const int answered = tree.query(p.p).label;
    if (p.mover == 0) {
      ++st;
      st_ok += node && tree.isNodeOccupied(node) && answered == p.gt;
    } else {
      ++dy;
      dy_ok += answered != majorityClass(movers[p.mover]);
    }
  }
  Shares all;
  double worst_free = 0.0;
  std::ostringstream each;
  for (const auto& [id, s] : per_mover) {
    all += s;
    worst_free = std::max(worst_free, share(s.free_ghosts, s.freed));
    each << (each.tellp() > 0 ? "," : "") << "{\"instance\":" << id << ",\"freed\":" << s.freed
         << ",\"ghost_share\":" << share(s.ghosts, s.freed)
         << ",\"free_ghost_share\":" << share(s.free_ghosts, s.freed) << "}";
  }
  std::cout << "{\"settings\":\"" << label << "\",\"lag\":" << lag << ",\"freed\":" << all.freed
            << ",\"ghost_share\":" << share(all.ghosts, all.freed)
            << ",\"free_ghost_share\":" << share(all.free_ghosts, all.freed)
            << ",\"worst_free_ghost_share\":" << worst_free
            << ",\"occupied_share\":" << share(all.occupied, all.freed)
            << ",\"plain_occupied_share\":" << share(all.plain_occupied, all.freed)
            << ",\"static_accuracy\":" << share(st_ok, st)
            << ",\"dynamic_accuracy\":" << share(dy_ok, dy) << ",\"movers\":[" << each.str()
            << "]}" << std::endl;
}

// Every row's map and plain OctoMap's, fed the same scans in turn.
void run(const Dataset& data, const evidential_octomap::ClassTable& classes,
         std::map<int, Mover>& movers, const std::vector<evbench::SettingsRow>& rows, int lag) {
  const std::vector<Point> points = collectPoints(data, movers);
  std::vector<EvidentialOcTree> trees;
  trees.reserve(rows.size());
  for (const auto& row : rows) {
    trees.emplace_back(0.2, classes.numClasses(), row.config);
    trees.back().setClasses(classes);
  }
  octomap::OcTree plain(0.2);
  for (size_t i = 0; i < data.size(); ++i) {
    const Scan scan = data.load(i);
    const octomap::point3d origin(scan.originW().x(), scan.originW().y(), scan.originW().z());
    const octomap::Pointcloud cloud = scan.pointsW();
    for (EvidentialOcTree& tree : trees) tree.insertSemanticScan(cloud, scan.evidence, origin);
    evbench::plainInsert(plain, cloud, origin, -1.0, true);
    for (auto& [id, m] : movers) {
      const auto box = m.boxes.find(int(i));
      if (box == m.boxes.end()) continue;
      for (const Key& key : boxVoxels(box->second, plain)) {
        const auto& [x, y, z] = key;
        const octomap::OcTreeNode* p = plain.search(octomap::OcTreeKey(x, y, z));
        m.covered[key] = {int(i), p ? p->getLogOdds() : std::numeric_limits<float>::infinity()};
      }
    }
  }
  // At the end, every voxel a mover left at least `lag` scans before.
  std::vector<std::vector<std::pair<int, Shares>>> per_mover(rows.size());
  const int end = int(data.size()) - 1;
  for (auto& [id, m] : movers)
    for (size_t r = 0; r < rows.size(); ++r)
      per_mover[r].push_back({id, measure(trees[r], plain, m, majorityClass(m), end, lag)});
  for (size_t r = 0; r < rows.size(); ++r)
    printRow(rows[r].label, trees[r], points, movers, per_mover[r], lag);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int lag = 10;
    std::string dir;
    std::vector<evbench::SettingsRow> rows;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--lag" && i + 1 < argc) {
        lag = std::stoi(argv[++i]);
      } else if (dir.empty()) {
        dir = a;
      } else {
        rows.push_back(evbench::parseSettingsRow(a));
      }
    }
    if (rows.empty() || lag < 1) {
      std::cerr << "usage: moving_objects [--lag N] DATASET "
                   "LABEL:defaults|FILE.yaml[:key=value,...]...\n";
      return 2;
    }
    const auto table = evidential_octomap::ClassTable::load(dir + "/classes.yaml");
    const Dataset data = Dataset::open(dir, table);
    auto movers = readMovers(dir + "/movers.csv");
    run(data, table, movers, rows, lag);
  } catch (const std::exception& e) {
    std::cerr << "moving_objects: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
