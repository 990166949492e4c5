// The methods the benchmarks time: plain OctoMap and the semantic insert with given settings,
// each with its own map and its measurements per step. Bench-only.
#pragma once

#include <evidential_octomap/class_table.h>
#include <evidential_octomap/evidential_octree.h>
#include <octomap/OcTree.h>
#include <time.h>

#include <algorithm>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "bench_data.h"
#include "plain_octomap.h"

namespace evbench {

using evidential_octomap::EvidentialOcTree;
using evidential_octomap::InsertStats;
using evidential_octomap::SemanticConfig;

inline double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

// The phases a row reports: the first pass over the scans (a map still filling) and the steady
// state of the revisit (steps 10-29: the map already knows the area).
struct Phase {
  std::string name, tag;
  size_t begin, end;  // steps [begin, end)
};
// One method: its map and its measurements, per scan index (all repeats).
struct Method {
  std::string label;  // table row
  std::string key;    // JSON / summary key: plain, plain_discretize, exact, exact_1t, fast, ...
  double max_range = -1.0;
  int threads = 1;
  bool learned = false;  // learned (cross-fitted) evidence, else derived one-hot
  std::vector<std::vector<double>> wall, cpu, main_cpu;  // ms [scan][repeat]
  std::vector<std::vector<InsertStats>> stats;           // semantic only

  virtual ~Method() = default;
  // A new empty map; a semantic map takes the class table's classes (ground and movable flags).
  virtual void reset(double resolution, const evidential_octomap::ClassTable& classes) = 0;
  virtual InsertStats insert(const Scan& scan, const std::vector<float>& evidence) = 0;

  void step(size_t i, const Scan& scan, const std::vector<float>& evidence) {
    if (wall.size() <= i)
      wall.resize(i + 1), cpu.resize(i + 1), main_cpu.resize(i + 1), stats.resize(i + 1);
    const double cpu0 = processCpuMs(), main0 = threadCpuMs();
    const auto start = Clock::now();
    const InsertStats s = insert(scan, evidence);
    wall[i].push_back(msSince(start));
    cpu[i].push_back(processCpuMs() - cpu0);
    main_cpu[i].push_back(threadCpuMs() - main0);
    stats[i].push_back(s);
  }
  static double sum(const std::vector<std::vector<double>>& v) {
    double s = 0.0;
    for (const auto& r : v) s += std::accumulate(r.begin(), r.end(), 0.0);
    return s;
  }
  static double medianOf(const std::vector<std::vector<double>>& v) {
    std::vector<double> all;
    for (const auto& r : v) all.insert(all.end(), r.begin(), r.end());
    return median(all);
  }
  // The same over the steps of one phase.
  static std::vector<std::vector<double>> slice(const std::vector<std::vector<double>>& v,
                                                const Phase& p) {
    const size_t end = std::min(p.end, v.size());
    return {v.begin() + std::min(p.begin, end), v.begin() + end};
  }
  // Median over every step of one InsertStats field.
  double medianStat(double InsertStats::*field) const {
    std::vector<double> all;
    for (const auto& r : stats)
      for (const auto& s : r) all.push_back(s.*field);
    return median(all);
  }
  double sumStat(double InsertStats::*field) const {
    double total = 0.0;
    for (const auto& r : stats)
      for (const auto& s : r) total += s.*field;
    return total;
  }
  // Share of the CPU work that ran in parallel: the worker threads' CPU (process minus calling
  // thread) is the parallel work's share beyond the caller's own part of it.
  double parallelShare() const {
    const double total = sum(cpu), workers = total - sum(main_cpu);
    return threads < 2 || total <= 0.0 ? 0.0
                                       : std::min(1.0, workers * threads / (threads - 1) / total);
  }
};

struct PlainMethod : Method {
  bool discretize = false;
  std::unique_ptr<octomap::OcTree> tree;
  void reset(double resolution, const evidential_octomap::ClassTable&) override {
    tree = std::make_unique<octomap::OcTree>(resolution);
  }
  InsertStats insert(const Scan& scan, const std::vector<float>&) override {
    plainInsert(*tree, scan.points_W, scan.origin_W, max_range, discretize);
    return {};
  }
};

struct SemanticMethod : Method {
  SemanticConfig config;
  std::unique_ptr<EvidentialOcTree> tree;
  void reset(double resolution, const evidential_octomap::ClassTable& classes) override {
    config.max_range = max_range;
    config.threads = threads;
    tree = std::make_unique<EvidentialOcTree>(resolution, classes.numClasses(), config);
    tree->setClasses(classes);
  }
  InsertStats insert(const Scan& scan, const std::vector<float>& evidence) override {
    return tree->insertSemanticScan(scan.points_W, evidence, scan.origin_W);
  }
};

inline std::unique_ptr<Method> plainMethod(double range, bool discretize) {
  auto m = std::make_unique<PlainMethod>();
  m->label =
      discretize ? "plain OcTree::insertPointCloud, discretize" : "plain OcTree::insertPointCloud";
  m->key = discretize ? "plain_discretize" : "plain";
  m->max_range = range;
  m->discretize = discretize;
  return m;
}

inline std::unique_ptr<Method> semanticMethod(double range, int threads, bool fast,
                                              const std::string& rule, bool learned = false) {
  auto m = std::make_unique<SemanticMethod>();
  m->label = std::string(fast ? "semantic insert, fast free space" : "semantic insert, exact") +
             (rule == "dempster" ? "" : " (" + rule + ")") +
             (learned ? ", learned (cross-fitted) evidence" : "");
  m->key = std::string(fast ? "fast" : "exact") + (rule == "dempster" ? "" : "_" + rule) +
           (learned ? "_learned" : "") + (threads == 1 ? "_1t" : "");
  m->max_range = range;
  m->threads = threads;
  m->learned = learned;
  m->config.rule = rule;
  m->config.fast_free_space = fast;
  return m;
}

// The live launch's settings (config/mapping_live.yaml): kernel length 0.2 m, count cap
// ds_multiplier 2, evidence floor 0.01, semantic evidence on the surface only.
inline std::unique_ptr<Method> liveMethod(double range, bool learned) {
  auto m = semanticMethod(range, 2, false, "dempster", learned);
  m->label = std::string(
                 "live launch settings (length_scale 0.2, ds_multiplier 2, evidence_floor 0.01, "
                 "semantic_occupied_only)") +
             (learned ? ", learned (cross-fitted) evidence" : "");
  m->key = std::string("live") + (learned ? "_learned" : "");
  SemanticConfig& config = static_cast<SemanticMethod&>(*m).config;
  config.length_scale = 0.2;
  config.ds_multiplier = 2.0;
  config.evidence_floor = 0.01;
  config.semantic_occupied_only = true;
  return m;
}

}  // namespace evbench
