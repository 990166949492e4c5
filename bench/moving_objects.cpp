// Moving objects on a generated sequence (SYNTHETIC, `evidential_octomap generate`): maps it once
// per movable_clearing_observations value (the class table's movable classes, the library
// defaults otherwise) and reports, per mover, the share of its swept volume that
// still answers its class `lag` scans after it left (of the swept voxels that are free and were
// cleared since it left), and at the end a DynamicMap_Benchmark-style
// static / dynamic accuracy over every point of the sequence:
//   static accuracy  = share of static points whose voxel is occupied and answers their class;
//   dynamic accuracy = share of mover points whose voxel no longer answers the mover's class.
// Usage: moving_objects <dataset> <M,M,...> [lag=10]   (prints one JSON line per M)
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evidential_octree.h"

using evidential_octomap::EvidentialOcTree;
using evidential_octomap::SemanticConfig;
using evidential_octomap::Dataset;
using evidential_octomap::readLabelFile;
using evidential_octomap::Scan;

namespace {

struct Box {
  double x, y, z, yaw, length, width, height;
};

struct Mover {
  std::vector<Box> boxes;
  std::map<std::tuple<int, int, int>, float> left;  // swept voxels' log-odds when it left
  int last_scan = -1;
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
    m.boxes.push_back({std::stod(f[3]), std::stod(f[4]), std::stod(f[5]), std::stod(f[6]),
                       std::stod(f[7]), std::stod(f[8]), std::stod(f[9])});
    m.last_scan = std::max(m.last_scan, std::stoi(f[0]));
  }
  return movers;
}

using KeySet = std::set<std::tuple<int, int, int>>;

// Voxels whose centre lies in one of the mover's boxes (the swept volume).
KeySet sweptVoxels(const Mover& m, const EvidentialOcTree& tree) {
  KeySet keys;
  const double r = tree.getResolution();
  for (const Box& b : m.boxes) {
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
            keys.insert({k[0], k[1], k[2]});
        }
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

void run(const Dataset& data, const evidential_octomap::ClassTable& classes,
         std::map<int, Mover>& movers, int k, int lag, std::vector<Point>* points, bool collect) {
  SemanticConfig config;
  config.movable_clearing_observations = k;
  EvidentialOcTree tree(0.2, classes.numClasses(), config);
  tree.setClasses(classes);
  std::ostringstream ghosts;
  double freed_total = 0, ghost_total = 0;
  for (size_t i = 0; i < data.size(); ++i) {
    Scan scan = data.load(i);
    if (collect) {
      const auto raw = readLabelFile(data.path() + "/labels/" + scan.name + ".label");
      for (size_t j = 0; j < scan.size(); ++j) {
        const Eigen::Vector3f w = scan.pointW(j);
        const int instance = int(raw[j] >> 16);
        points->push_back({octomap::point3d(w.x(), w.y(), w.z()), scan.gt[j], instance});
        if (instance) ++movers[instance].classes[scan.gt[j]];
      }
    }
    tree.insertSemanticScan(scan.pointsW(), scan.evidence,
                            octomap::point3d(scan.originW().x(), scan.originW().y(),
                                             scan.originW().z()));
    for (auto& [id, m] : movers) {
      if (m.last_scan == int(i) && m.last_scan + lag < int(data.size())) {
        for (const auto& [x, y, z] : sweptVoxels(m, tree)) {
          const auto* node = tree.search(octomap::OcTreeKey(x, y, z));
          m.left[{x, y, z}] = node ? node->getLogOdds() : 0.0f;
        }
      }
      if (m.last_scan + lag != int(i)) continue;
      const int cls = majorityClass(m);
      // Freed: free now and cleared since it left (log-odds lower than then).
      size_t freed = 0, ghost = 0;
      for (const auto& [key, then] : m.left) {
        const auto& [x, y, z] = key;
        const auto* node = tree.search(octomap::OcTreeKey(x, y, z));
        if (!node || tree.isNodeOccupied(node) || !(node->getLogOdds() < then)) continue;
        ++freed;
        if (tree.opinion(node).label == cls) ++ghost;
      }
      m.left.clear();
      ghosts << (ghosts.tellp() > 0 ? "," : "") << "{\"instance\":" << id << ",\"class\":" << cls
             << ",\"freed\":" << freed << ",\"ghost_share\":" << (freed ? double(ghost) / freed : 0)
             << "}";
      freed_total += freed, ghost_total += ghost;
    }
  }
  size_t st = 0, st_ok = 0, dy = 0, dy_ok = 0;
  for (const Point& p : *points) {
    const auto* node = tree.nodeAt(p.p);
    const int label = tree.opinion(node).label;
    if (p.mover == 0) {
      ++st;
      st_ok += node && tree.isNodeOccupied(node) && label == p.gt;
    } else {
      ++dy;
      dy_ok += label != majorityClass(movers[p.mover]);
    }
  }
  std::cout << "{\"movable_clearing_observations\":" << k << ",\"lag\":" << lag
            << ",\"ghost_share\":" << (freed_total ? ghost_total / freed_total : 0)
            << ",\"freed_voxels\":" << freed_total << ",\"static_accuracy\":" << double(st_ok) / st
            << ",\"dynamic_accuracy\":" << (dy ? double(dy_ok) / dy : 0) << ",\"movers\":["
            << ghosts.str() << "]}" << std::endl;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: moving_objects <dataset> <M,M,...> [lag=10]\n";
    return 2;
  }
  const std::string dir = argv[1];
  const int lag = argc > 3 ? std::stoi(argv[3]) : 10;
  const auto table = evidential_octomap::ClassTable::load(dir + "/classes.yaml");
  const Dataset data = Dataset::open(dir, table);
  auto movers = readMovers(dir + "/movers.csv");
  std::vector<Point> points;
  std::stringstream ks(argv[2]);
  bool first = true;
  for (std::string k; std::getline(ks, k, ',');) {
    run(data, table, movers, std::stoi(k), lag, &points, first);
    first = false;
  }
  return 0;
}
