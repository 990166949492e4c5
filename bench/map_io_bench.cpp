// evidential_map_io_bench: save, load and query of a (long) map against plain OctoMap on the
// same occupancy, and optionally a leaf-by-leaf comparison with a second map.
//
//   evidential_map_io_bench MAP.ot [--same-as OTHER.ot] [--queries N] [--repeats R]
//
// Times (median of R, wall and CPU of the process): loadMap(MAP.ot); the map's occupancy written
// as .bt and read back by plain octomap::OcTree::readBinary; saveMap; N queries at random points
// in random leaves of the map (known space, fixed seed), against OcTree::search of the same
// points. Prints one JSON object. --same-as: leaves of either map missing in the other, leaves
// whose label or occupied/free state differ, and the largest payload difference relative to
// the payload.
// Timers and counts only; nothing here is a test.
#include <evidential_octomap/evidential_octree.h>
#include <evidential_octomap/io.h>
#include <octomap/OcTree.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_data.h"

namespace eo = evidential_octomap;

namespace {

struct Cost {
  double wall_ms, cpu_ms;
};

// Median wall and CPU of `repeats` calls of `run`.
Cost timed(int repeats, const std::function<void()>& run) {
  std::vector<double> wall, cpu;
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = evbench::Clock::now();
    const double c0 = evbench::processCpuMs();
    run();
    cpu.push_back(evbench::processCpuMs() - c0);
    wall.push_back(std::chrono::duration<double, std::milli>(evbench::Clock::now() - t0).count());
  }
  return {evbench::median(wall), evbench::median(cpu)};
}

double fileMb(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) throw std::runtime_error("cannot stat " + path);
  return st.st_size / 1e6;
}

// n points drawn uniformly among the map's leaves (known space, where a planner asks), each at
// a random offset inside its leaf; fixed seed.
std::vector<octomap::point3d> pointsInLeaves(const eo::EvidentialOcTree& map, size_t n) {
  std::mt19937 rng(7);
  std::vector<std::pair<octomap::point3d, double>> picked;  // reservoir: centre, leaf size
  size_t seen = 0;
  for (auto it = map.begin_leafs(), end = map.end_leafs(); it != end; ++it, ++seen) {
    const auto leaf = std::make_pair(it.getCoordinate(), it.getSize());
    if (picked.size() < n) {
      picked.push_back(leaf);
    } else {
      const size_t slot = std::uniform_int_distribution<size_t>(0, seen)(rng);
      if (slot < n) picked[slot] = leaf;
    }
  }
  std::uniform_real_distribution<double> offset(-0.499, 0.499);
  std::vector<octomap::point3d> pts;
  for (const auto& [c, size] : picked)
    pts.emplace_back(c.x() + offset(rng) * size, c.y() + offset(rng) * size,
                     c.z() + offset(rng) * size);
  std::shuffle(pts.begin(), pts.end(), rng);  // no tree order: each query finds its own path
  return pts;
}

// Leaf-by-leaf differences between two maps of one resolution and class count.
void compare(const eo::EvidentialOcTree& a, const eo::EvidentialOcTree& b) {
  size_t missing = 0, labels = 0, states = 0, leaves = 0;
  double worst = 0.0;
  const auto one_way = [&](const eo::EvidentialOcTree& x, const eo::EvidentialOcTree& y,
                           bool count_values) {
    for (auto it = x.begin_leafs(), end = x.end_leafs(); it != end; ++it) {
      const auto* other = y.search(it.getKey(), it.getDepth());
      if (!other || y.nodeHasChildren(other)) {
        ++missing;
        continue;
      }
      if (!count_values) continue;
      ++leaves;
      if (x.isNodeOccupied(*it) != y.isNodeOccupied(other)) ++states;
      if (x.opinion(&*it).label != y.opinion(other).label) ++labels;
      const auto p = x.payload(&*it), q = y.payload(other);
      if (p.size() != q.size()) {
        ++labels;
        continue;
      }
      for (size_t c = 0; c < p.size(); ++c)
        worst =
            std::max(worst, std::abs(double(p[c]) - q[c]) / std::max(1e-6, std::abs(double(p[c]))));
    }
  };
  one_way(a, b, true);
  one_way(b, a, false);
  std::printf(
      ",\"compare\":{\"leaves\":%zu,\"leaves_missing_in_either\":%zu,\"labels_differ\":%zu,"
      "\"occupied_state_differs\":%zu,\"largest_relative_payload_difference\":%.3g}",
      leaves, missing, labels, states, worst);
}

void run(const std::string& path, const std::string& same_as, size_t queries, int repeats) {
  const std::string bt = path + ".bench.bt", ot = path + ".bench.ot";
  std::unique_ptr<eo::EvidentialOcTree> map;
  const Cost load = timed(repeats, [&] { map = eo::loadMap(path); });
  const double rss_loaded = evbench::currentRssMb();
  const Cost save = timed(repeats, [&] { eo::saveMap(*map, ot); });
  eo::saveBinaryOccupancy(*map, bt);
  std::unique_ptr<octomap::OcTree> plain;
  const Cost read_bt = timed(repeats, [&] {
    plain = std::make_unique<octomap::OcTree>(map->getResolution());
    if (!plain->readBinary(bt)) throw std::runtime_error("readBinary failed on " + bt);
  });
  const auto pts = pointsInLeaves(*map, queries);
  size_t known = 0, labelled = 0, plain_known = 0;
  const Cost query = timed(1, [&] {
    for (const auto& p : pts) {
      const auto o = map->query(p);
      labelled += o.label >= 0;
      known += map->search(p) != nullptr;
    }
  });
  const Cost search = timed(1, [&] {
    for (const auto& p : pts) plain_known += plain->search(p) != nullptr;
  });
  std::printf(
      "{\"map\":\"%s\",\"ot_mb\":%.2f,\"bt_mb\":%.2f,\"leaves\":%zu,\"semantic_leaves\":%zu,"
      "\"memory_usage_mb\":%.1f,\"rss_after_load_mb\":%.1f,"
      "\"load_ms\":[%.0f,%.0f],\"plain_read_binary_ms\":[%.0f,%.0f],\"save_ms\":[%.0f,%.0f],"
      "\"queries\":%zu,\"query_us\":%.3f,\"plain_search_us\":%.3f,\"queries_known\":%zu,"
      "\"queries_labelled\":%zu,\"plain_queries_known\":%zu",
      path.c_str(), fileMb(path), fileMb(bt), map->getNumLeafNodes(), map->numSemanticNodes(),
      map->memoryUsage() / 1e6, rss_loaded, load.wall_ms, load.cpu_ms, read_bt.wall_ms,
      read_bt.cpu_ms, save.wall_ms, save.cpu_ms, queries, 1e3 * query.wall_ms / queries,
      1e3 * search.wall_ms / queries, known, labelled, plain_known);
  std::remove(bt.c_str());
  std::remove(ot.c_str());
  if (!same_as.empty()) {
    plain.reset();
    compare(*map, *eo::loadMap(same_as));
  }
  std::printf("}\n");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 2)
      throw std::invalid_argument(
          "usage: evidential_map_io_bench MAP.ot [--same-as B.ot] [--queries N] [--repeats R]");
    std::string same_as;
    size_t queries = 1000000;
    int repeats = 3;
    for (int i = 2; i + 1 < argc; i += 2) {
      const std::string flag = argv[i], value = argv[i + 1];
      if (flag == "--same-as")
        same_as = value;
      else if (flag == "--queries")
        queries = std::stoul(value);
      else if (flag == "--repeats")
        repeats = std::stoi(value);
      else
        throw std::invalid_argument("unknown argument " + flag);
    }
    run(argv[1], same_as, queries, repeats);
  } catch (const std::exception& e) {
    std::cerr << "evidential_map_io_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
