// evidential_bench: the performance table of DESIGN §8 / issue 7, measured in one run.
//
// On the bundled SemanticKITTI scans (world frame, derived one-hot evidence of magnitude 20) it
// times, per scan and with the map growing scan by scan:
//   - EvidentialOcTree::insertSemanticScan (full semantic + occupancy insert), 1 and 2 threads,
//     split by phase (InsertStats), against plain octomap::OcTree::insertPointCloud with the same
//     resolution and max range (discretize = false, OctoMap's default, and discretize = true, which
//     is what our integrator uses by default);
//   - the three fusion rules; scaling with points per scan; publishing / serialising cost;
//   - memory: node sizes, bytes per free / semantic leaf, memoryUsage(), peak RSS, .ot size.
// Writes JSON (--json) and markdown tables (--md) and prints a summary of the key ratios.
// Wall-clock timers only; nothing here is a test.
#include <omp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include <evidential_octomap/evidential_octree.h>
#include <evidential_octomap/io.h>

#include "bench_data.h"
#include "fast_occupancy.h"
#include "json_writer.h"
#include "plain_octomap.h"

using evbench::Clock;
using evbench::Json;
using evbench::Scan;
using evbench::median;
using evbench::msSince;
using evidential_octomap::EvidentialOcTree;
using evidential_octomap::EvidentialOcTreeNode;
using evidential_octomap::SemanticConfig;

namespace {

struct Options {
  std::string data = "data/semantickitti_08_first10";
  std::string classes = "config/classes_semantickitti.yaml";
  int scans = 10;
  double resolution = 0.2;
  int repeats = 1;
  int scaling_scans = 3;
  std::vector<size_t> scaling_points{10000, 30000, 60000, 120000};
  bool quick = false;       // fewer configurations (smoke run)
  bool prototype = true;    // run the bench-only fast occupancy prototype
  std::string json_path;
  std::string md_path;
  std::string rss_child;    // internal: "plain" or "semantic"
  double rss_range = -1.0;
  int rss_threads = 2;
};

// ---------------------------------------------------------------------------------------------
// Results of one configuration over the scan sequence (per scan index, median over repeats).
struct Series {
  std::string name;
  std::string kind;  // "plain", "semantic", "prototype"
  double max_range = -1.0;
  int threads = 1;
  bool discretize = false;
  std::string rule;
  std::vector<std::vector<double>> total, occupancy, kernel, update;  // wall ms [scan][repeat]
  std::vector<std::vector<double>> cpu;                               // process CPU ms
  std::vector<size_t> points;                                        // per scan
  size_t semantic_points = 0, voxels_updated = 0;                    // summed over the sequence
  evbench::MapFingerprint fingerprint;                               // final map (plain, prototype)

  std::vector<double> medians(const std::vector<std::vector<double>>& v) const {
    std::vector<double> out;
    for (const auto& r : v) out.push_back(median(r));
    return out;
  }
  double sum(const std::vector<std::vector<double>>& v) const {
    const auto m = medians(v);
    return std::accumulate(m.begin(), m.end(), 0.0);
  }
  double medianOfScans(const std::vector<std::vector<double>>& v) const { return median(medians(v)); }
  size_t totalPoints() const { return std::accumulate(points.begin(), points.end(), size_t(0)); }
};

void record(std::vector<std::vector<double>>& v, size_t scan, double value) {
  if (v.size() <= scan) v.resize(scan + 1);
  v[scan].push_back(value);
}

// ---------------------------------------------------------------------------------------------
// Map statistics (memory section).
struct TreeStats {
  size_t nodes = 0, leaves = 0, inner = 0;
  size_t occupied_leaves = 0, free_leaves = 0, semantic_leaves = 0, pruned_leaves = 0;
  size_t zero_log_odds_leaves = 0;  // never hit or missed by a ray (kernel-created leaves)
  size_t semantic_nodes = 0;  // payload slots in use (leaves and inner summaries)
  size_t memory_usage = 0;    // tree.memoryUsage()
  size_t memory_nodes = 0;    // OctoMap's own part (nodes + child arrays)
  double write_ms = 0.0;      // tree.write(stringstream)
  size_t write_bytes = 0;
  size_t ot_bytes = 0;        // saveMap / OcTree::write to /tmp
};

template <typename Tree>
void countLeaves(const Tree& tree, TreeStats* s) {
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    ++s->leaves;
    if (tree.isNodeOccupied(*it)) ++s->occupied_leaves; else ++s->free_leaves;
    if (it.getDepth() < tree.getTreeDepth()) ++s->pruned_leaves;
    if (it->getLogOdds() == 0.0f) ++s->zero_log_odds_leaves;
  }
  s->nodes = tree.size();
  s->inner = s->nodes - s->leaves;
}

size_t fileSize(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0 ? static_cast<size_t>(st.st_size) : 0;
}

TreeStats semanticTreeStats(const EvidentialOcTree& tree) {
  TreeStats s;
  countLeaves(tree, &s);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (it->hasSemantics()) ++s.semantic_leaves;
  }
  s.semantic_nodes = tree.numSemanticNodes();
  s.memory_usage = tree.memoryUsage();
  s.memory_nodes = tree.octomap::OccupancyOcTreeBase<EvidentialOcTreeNode>::memoryUsage();
  std::stringstream buffer;
  const auto start = Clock::now();
  tree.write(buffer);
  s.write_ms = msSince(start);
  s.write_bytes = buffer.str().size();
  const std::string path = "/tmp/evidential_bench_" + std::to_string(getpid()) + ".ot";
  evidential_octomap::saveMap(tree, path);
  s.ot_bytes = fileSize(path);
  std::remove(path.c_str());
  return s;
}

TreeStats plainTreeStats(const octomap::OcTree& tree) {
  TreeStats s;
  countLeaves(tree, &s);
  s.memory_usage = s.memory_nodes = tree.memoryUsage();
  std::stringstream buffer;
  const auto start = Clock::now();
  tree.write(buffer);
  s.write_ms = msSince(start);
  s.write_bytes = buffer.str().size();
  const std::string path = "/tmp/evidential_bench_plain_" + std::to_string(getpid()) + ".ot";
  tree.write(path);
  s.ot_bytes = fileSize(path);
  std::remove(path.c_str());
  return s;
}

Json statsJson(const TreeStats& s) {
  Json j = Json::object();
  j.set("nodes", s.nodes).set("leaves", s.leaves).set("inner_nodes", s.inner);
  j.set("occupied_leaves", s.occupied_leaves).set("free_leaves", s.free_leaves);
  j.set("zero_log_odds_leaves", s.zero_log_odds_leaves);
  j.set("pruned_leaves", s.pruned_leaves).set("semantic_leaves", s.semantic_leaves);
  j.set("semantic_nodes", s.semantic_nodes).set("memory_usage_bytes", s.memory_usage);
  j.set("memory_nodes_bytes", s.memory_nodes).set("write_ms", s.write_ms);
  j.set("write_bytes", s.write_bytes).set("ot_bytes", s.ot_bytes);
  return j;
}

// ---------------------------------------------------------------------------------------------
// Publishing cost, as the ROS node does it (src/ros: occupiedVoxels -> markers / PointCloud2,
// and the map message = tree.write into a stringstream), without ROS serialisation.
struct PublishCost {
  double views_ms = 0.0;  // occupied-leaf iteration + opinion read-out + marker/cloud buffers
  double map_ms = 0.0;    // tree.write(stringstream) + copy into a byte vector
  size_t voxels = 0;
  size_t map_bytes = 0;
};

PublishCost publishCost(const EvidentialOcTree& tree) {
  PublishCost cost;
  auto start = Clock::now();
  struct View { float x, y, z, size; int label; float u; unsigned depth; };
  std::vector<View> views;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const auto opinion = tree.opinion(&*it);
    const auto c = it.getCoordinate();
    views.push_back({c.x(), c.y(), c.z(), float(it.getSize()), opinion.label, opinion.uncertainty,
                     it.getDepth()});
  }
  // One CUBE_LIST per depth (points + colours) and a PointCloud2 buffer (x y z rgb label u).
  std::vector<std::vector<float>> markers(tree.getTreeDepth() + 1);
  std::vector<uint8_t> cloud(views.size() * 24);
  for (size_t i = 0; i < views.size(); ++i) {
    const View& v = views[i];
    auto& m = markers[v.depth];
    m.insert(m.end(), {v.x, v.y, v.z, 1.0f, 0.5f, 0.5f, 1.0f});
    const float row[6] = {v.x, v.y, v.z, 0.0f, float(v.label), v.u};
    std::memcpy(&cloud[i * 24], row, 24);
  }
  cost.views_ms = msSince(start);
  cost.voxels = views.size();
  start = Clock::now();
  std::stringstream s;
  tree.write(s);
  const std::string bytes = s.str();
  std::vector<uint8_t> data(bytes.begin(), bytes.end());
  cost.map_ms = msSince(start);
  cost.map_bytes = data.size();
  return cost;
}

// ---------------------------------------------------------------------------------------------
// Runners. Every run builds a fresh map and inserts the scans in order.

struct Runner {
  const std::vector<Scan>& scans;
  int num_classes;
  double resolution;
  std::vector<std::vector<float>> evidence;  // derived, precomputed (not timed)

  Runner(const std::vector<Scan>& s, int c, double r) : scans(s), num_classes(c), resolution(r) {
    for (const auto& scan : scans) evidence.push_back(evbench::derivedEvidence(scan.classes, c));
  }

  void plain(Series* series, TreeStats* stats) const {
    octomap::OcTree tree(resolution);
    for (size_t i = 0; i < scans.size(); ++i) {
      const double cpu0 = evbench::processCpuMs();
      const double ms = evbench::plainInsert(tree, scans[i].points_W, scans[i].origin_W,
                                             series->max_range, series->discretize);
      record(series->cpu, i, evbench::processCpuMs() - cpu0);
      record(series->total, i, ms);
      if (series->points.size() <= i) series->points.push_back(scans[i].points_W.size());
    }
    series->fingerprint = evbench::fingerprint(tree);
    if (stats) *stats = plainTreeStats(tree);
  }

  // OctoMap's insertPointCloud split into key computation and node updates (same code path).
  void plainPhases(Series* series) const {
    octomap::OcTree tree(resolution);
    for (size_t i = 0; i < scans.size(); ++i) {
      const double cpu0 = evbench::processCpuMs();
      const auto start = Clock::now();
      const auto t = evbench::plainInsertPhases(&tree, scans[i].points_W, scans[i].origin_W,
                                                series->max_range, series->discretize);
      record(series->total, i, msSince(start));
      record(series->cpu, i, evbench::processCpuMs() - cpu0);
      record(series->occupancy, i, t.ms_keys);
      record(series->update, i, t.ms_update);
      record(series->kernel, i, 0.0);
      if (series->points.size() <= i) series->points.push_back(scans[i].points_W.size());
    }
    series->fingerprint = evbench::fingerprint(tree);
  }

  void prototype(Series* series) const {
    omp_set_num_threads(series->threads);
    octomap::OcTree tree(resolution);
    evbench::FastOccupancy fast(series->threads);
    for (size_t i = 0; i < scans.size(); ++i) {
      const double cpu0 = evbench::processCpuMs();
      const auto start = Clock::now();
      const auto t = fast.insert(&tree, scans[i].points_W, scans[i].origin_W, series->max_range,
                                 series->discretize);
      record(series->total, i, msSince(start));
      record(series->cpu, i, evbench::processCpuMs() - cpu0);
      record(series->occupancy, i, t.ms_keys);
      record(series->update, i, t.ms_update);
      record(series->kernel, i, 0.0);
      if (series->points.size() <= i) series->points.push_back(scans[i].points_W.size());
    }
    series->fingerprint = evbench::fingerprint(tree);
  }

  void semantic(Series* series, TreeStats* stats, std::vector<PublishCost>* publish) const {
    SemanticConfig config;
    config.rule = series->rule;
    config.max_range = series->max_range;
    config.threads = series->threads;
    config.discretize = series->discretize;
    // OctoMap sizes its per-thread key rays at construction from omp_get_max_threads() and its
    // computeUpdate sets the OpenMP thread count from them: set the count before the tree exists.
    omp_set_num_threads(series->threads);
    EvidentialOcTree tree(resolution, num_classes, config);
    for (size_t i = 0; i < scans.size(); ++i) {
      const double cpu0 = evbench::processCpuMs();
      const auto start = Clock::now();
      const auto s = tree.insertSemanticScan(scans[i].points_W, evidence[i], scans[i].origin_W);
      record(series->total, i, msSince(start));
      record(series->cpu, i, evbench::processCpuMs() - cpu0);
      record(series->occupancy, i, s.ms_occupancy);
      record(series->kernel, i, s.ms_kernel);
      record(series->update, i, s.ms_update);
      if (series->points.size() <= i) series->points.push_back(scans[i].points_W.size());
      if (series->total[i].size() == 1) {
        series->semantic_points += s.semantic_points;
        series->voxels_updated += s.voxels_updated;
      }
      if (publish) publish->push_back(publishCost(tree));
    }
    if (stats) *stats = semanticTreeStats(tree);
  }
};

Json seriesJson(const Series& s) {
  Json j = Json::object();
  j.set("name", s.name).set("kind", s.kind).set("max_range", s.max_range);
  j.set("threads", s.threads).set("discretize", s.discretize);
  if (!s.rule.empty()) j.set("rule", s.rule);
  j.set("repeats", s.total.empty() ? 0 : int(s.total[0].size()));
  j.set("ms_per_scan", s.medians(s.total));
  j.set("ms_per_scan_median", s.medianOfScans(s.total));
  j.set("ms_total", s.sum(s.total));
  j.set("cpu_ms_per_scan", s.medians(s.cpu));
  j.set("cpu_ms_per_scan_median", s.medianOfScans(s.cpu));
  j.set("cpu_ms_total", s.sum(s.cpu));
  const double points = double(s.totalPoints());
  j.set("points_per_scan", points / std::max<size_t>(1, s.points.size()));
  j.set("points_per_second", points / (s.sum(s.total) / 1000.0));
  if (!s.occupancy.empty()) {
    j.set("ms_occupancy", s.medians(s.occupancy));
    j.set("ms_kernel", s.medians(s.kernel));
    j.set("ms_update", s.medians(s.update));
    j.set("ms_occupancy_median", s.medianOfScans(s.occupancy));
    j.set("ms_kernel_median", s.medianOfScans(s.kernel));
    j.set("ms_update_median", s.medianOfScans(s.update));
    j.set("semantic_points", s.semantic_points).set("voxels_updated", s.voxels_updated);
  }
  return j;
}

// ---------------------------------------------------------------------------------------------
// Peak RSS of a separate process that maps the scans (so nothing else the bench did counts).

std::string selfPath() {
  char buffer[4096];
  const ssize_t n = readlink("/proc/self/exe", buffer, sizeof(buffer) - 1);
  if (n <= 0) throw std::runtime_error("cannot read /proc/self/exe");
  buffer[n] = '\0';
  return buffer;
}

std::map<std::string, double> runRssChild(const Options& o, const std::string& mode, double range) {
  std::ostringstream cmd;
  cmd << "'" << selfPath() << "' --data '" << o.data << "' --classes '" << o.classes
      << "' --scans " << o.scans << " --resolution " << o.resolution << " --rss-child " << mode
      << " --rss-range " << range << " --rss-threads " << o.rss_threads;
  std::map<std::string, double> out;
  FILE* pipe = popen(cmd.str().c_str(), "r");
  if (!pipe) return out;
  char line[512];
  while (std::fgets(line, sizeof(line), pipe)) {
    char key[128];
    double value;
    if (std::sscanf(line, "%127s %lf", key, &value) == 2) out[key] = value;
  }
  pclose(pipe);
  return out;
}

int rssChild(const Options& o) {
  int num_classes = 0;
  auto scans = evbench::loadKittiScans(o.data, o.classes, o.scans, &num_classes);
  const double before = evbench::currentRssMb();
  if (o.rss_child == "plain") {
    octomap::OcTree tree(o.resolution);
    for (const auto& s : scans) evbench::plainInsert(tree, s.points_W, s.origin_W, o.rss_range, true);
    std::printf("rss_after_map_mb %.3f\n", evbench::currentRssMb());
  } else {
    SemanticConfig config;
    config.max_range = o.rss_range;
    config.threads = o.rss_threads;
    omp_set_num_threads(o.rss_threads);
    EvidentialOcTree tree(o.resolution, num_classes, config);
    for (const auto& s : scans) {
      const auto evidence = evbench::derivedEvidence(s.classes, num_classes);
      tree.insertSemanticScan(s.points_W, evidence, s.origin_W);
    }
    std::printf("rss_after_map_mb %.3f\n", evbench::currentRssMb());
  }
  std::printf("rss_before_map_mb %.3f\npeak_rss_mb %.3f\n", before, evbench::peakRssMb());
  return 0;
}

// ---------------------------------------------------------------------------------------------

std::string fmt(double v, int decimals = 1) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, v);
  return buffer;
}

std::string rangeName(double r) { return r < 0 ? "-1 (unlimited)" : fmt(r, 0) + " m"; }

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--data") o.data = next();
    else if (a == "--classes") o.classes = next();
    else if (a == "--scans") o.scans = std::stoi(next());
    else if (a == "--resolution") o.resolution = std::stod(next());
    else if (a == "--repeats") o.repeats = std::max(1, std::stoi(next()));
    else if (a == "--scaling-scans") o.scaling_scans = std::stoi(next());
    else if (a == "--quick") o.quick = true;
    else if (a == "--no-prototype") o.prototype = false;
    else if (a == "--json") o.json_path = next();
    else if (a == "--md") o.md_path = next();
    else if (a == "--rss-child") o.rss_child = next();
    else if (a == "--rss-range") o.rss_range = std::stod(next());
    else if (a == "--rss-threads") o.rss_threads = std::stoi(next());
    else if (a == "--help" || a == "-h") {
      std::cout << "evidential_bench [--data DIR] [--classes YAML] [--scans N] [--resolution R]\n"
                   "  [--repeats N] [--scaling-scans N] [--quick] [--no-prototype]\n"
                   "  [--json PATH] [--md PATH]\n";
      std::exit(0);
    } else {
      throw std::invalid_argument("unknown argument " + a);
    }
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) try {
  const Options o = parse(argc, argv);
  if (!o.rss_child.empty()) return rssChild(o);

  int num_classes = 0;
  const auto scans = evbench::loadKittiScans(o.data, o.classes, o.scans, &num_classes);
  const Runner runner(scans, num_classes, o.resolution);
  std::cerr << "loaded " << scans.size() << " scans, C = " << num_classes << ", resolution "
            << o.resolution << " m\n";
  auto progress = [](const std::string& what) {
    std::cerr << "  " << what << std::endl;
  };

  // --- 1. main comparison: plain vs semantic, both max ranges, 1 and 2 threads ---------------
  std::vector<double> ranges{-1.0, 50.0};
  std::vector<Series> main_series;
  for (double r : ranges) {
    auto add = [&](const std::string& name, const std::string& kind, int threads, bool disc,
                   const std::string& rule) {
      Series s;
      s.name = name;
      s.kind = kind;
      s.max_range = r;
      s.threads = threads;
      s.discretize = disc;
      s.rule = rule;
      main_series.push_back(s);
    };
    add("plain OcTree::insertPointCloud", "plain", 1, false, "");
    add("plain OcTree::insertPointCloud, discretize", "plain", 1, true, "");
    if (!o.quick) add("EvidentialOcTree::insertSemanticScan", "semantic", 1, true, "dempster");
    add("EvidentialOcTree::insertSemanticScan", "semantic", 2, true, "dempster");
    if (o.prototype) add("bench prototype: fast occupancy (no semantics)", "prototype", 2, true, "");
  }
  TreeStats plain_stats, semantic_stats;
  std::vector<PublishCost> publish;
  for (int rep = 0; rep < o.repeats; ++rep) {
    for (auto& s : main_series) {
      progress("rep " + std::to_string(rep + 1) + "/" + std::to_string(o.repeats) + ": " + s.name +
               ", " + std::to_string(s.threads) + " thr, range " + fmt(s.max_range, 0) +
               (s.discretize ? ", discretize" : ""));
      const bool first = rep == 0;
      const bool ref = s.max_range < 0 && s.threads == 2;
      if (s.kind == "plain") {
        // Memory reference: the plain OcTree on the same rays as ours (discretize).
        runner.plain(&s, first && s.max_range < 0 && s.discretize ? &plain_stats : nullptr);
      } else if (s.kind == "prototype") {
        runner.prototype(&s);
      } else {
        runner.semantic(&s, first && ref ? &semantic_stats : nullptr,
                        first && ref ? &publish : nullptr);
      }
    }
  }

  // --- 2. fusion rules (2 threads, unlimited range) ------------------------------------------
  std::vector<Series> rule_series;
  for (const std::string rule : {"sbki", "ebs"}) {
    Series s;
    s.name = "EvidentialOcTree::insertSemanticScan";
    s.kind = "semantic";
    s.threads = 2;
    s.discretize = true;
    s.rule = rule;
    for (int rep = 0; rep < o.repeats; ++rep) {
      progress("rule " + rule);
      runner.semantic(&s, nullptr, nullptr);
    }
    rule_series.push_back(s);
  }

  // --- 2b. profile of plain OctoMap: key computation vs node updates (1 run) -----------------
  std::vector<Series> phase_series;
  for (double r : ranges) {
    Series s;
    s.name = "plain insertPointCloud discretize, phases";
    s.kind = "plain_phases";
    s.max_range = r;
    s.discretize = true;
    progress("plain phases, range " + fmt(r, 0));
    runner.plainPhases(&s);
    phase_series.push_back(s);
  }

  // --- 3. scaling with points per scan (first scaling_scans scans, random subsets) ------------
  struct ScalingRow {
    size_t points;
    Series plain, semantic;
  };
  std::vector<ScalingRow> scaling;
  {
    const int k = std::min<int>(o.scaling_scans, static_cast<int>(scans.size()));
    for (size_t target : o.scaling_points) {
      std::vector<Scan> subset;
      for (int i = 0; i < k; ++i) subset.push_back(evbench::subsample(scans[i], target, 7 + i));
      const Runner sub(subset, num_classes, o.resolution);
      ScalingRow row;
      row.points = subset[0].points_W.size();
      row.plain.max_range = row.semantic.max_range = -1.0;
      row.plain.threads = 1;
      row.semantic.threads = 2;
      row.semantic.discretize = true;
      row.semantic.rule = "dempster";
      for (int rep = 0; rep < o.repeats; ++rep) {
        progress("scaling " + std::to_string(target) + " points");
        sub.plain(&row.plain, nullptr);
        sub.semantic(&row.semantic, nullptr, nullptr);
      }
      scaling.push_back(row);
    }
  }

  // --- 4. memory -------------------------------------------------------------------------------
  progress("peak RSS (child processes)");
  auto rss_plain = runRssChild(o, "plain", -1.0);
  auto rss_sem = runRssChild(o, "semantic", -1.0);

  // ============================================================================================
  // Derived figures.
  auto find = [&](const std::string& kind, double r, int threads, bool disc) -> const Series& {
    for (const auto& s : main_series)
      if (s.kind == kind && s.max_range == r && s.threads == threads && s.discretize == disc) return s;
    throw std::logic_error("series not found");
  };
  const int C = num_classes;
  const size_t node_bytes = sizeof(EvidentialOcTreeNode);
  const size_t plain_node_bytes = sizeof(octomap::OcTreeNode);
  const double child_array = sizeof(void*) * 8.0;
  // OctoMap's memory model: every node sizeof(NODE), every inner node also an 8-pointer array.
  const double plain_per_leaf = double(plain_stats.memory_nodes) / std::max<size_t>(1, plain_stats.leaves);
  const double sem_tree_per_leaf =
      double(semantic_stats.memory_nodes) / std::max<size_t>(1, semantic_stats.leaves);
  const double pool_bytes = double(semantic_stats.memory_usage - semantic_stats.memory_nodes);
  const double pool_per_semantic_leaf = pool_bytes / std::max<size_t>(1, semantic_stats.semantic_leaves);
  const double semantic_leaf_bytes = node_bytes + pool_per_semantic_leaf;
  const double semantic_leaf_target = 16.0 + 4.0 * C;

  Json summary = Json::object();
  std::vector<std::pair<std::string, std::string>> summary_lines;
  auto sum_line = [&](const std::string& key, double value, const std::string& text) {
    summary.set(key, value);
    summary_lines.emplace_back(key, text);
  };
  for (double r : ranges) {
    const std::string tag = r < 0 ? "r-1" : "r50";
    const Series& plain = find("plain", r, 1, false);
    const Series& plain_d = find("plain", r, 1, true);
    const Series& sem2 = find("semantic", r, 2, true);
    const double ratio = sem2.sum(sem2.total) / plain.sum(plain.total);
    const double ratio_d = sem2.sum(sem2.total) / plain_d.sum(plain_d.total);
    sum_line("ratio_semantic2t_vs_plain_" + tag, ratio,
             "semantic insert (2 thr) / plain insertPointCloud, range " + rangeName(r) + ": " +
                 fmt(ratio, 3) + "x (target <= 1.0)");
    sum_line("ratio_semantic2t_vs_plain_discretize_" + tag, ratio_d,
             "semantic insert (2 thr) / plain insertPointCloud discretize, range " + rangeName(r) +
                 ": " + fmt(ratio_d, 3) + "x");
    const double cpu_ratio = sem2.sum(sem2.cpu) / plain.sum(plain.cpu);
    sum_line("cpu_ratio_semantic2t_vs_plain_" + tag, cpu_ratio,
             "CPU time (all threads) semantic insert (2 thr) / plain insertPointCloud, range " +
                 rangeName(r) + ": " + fmt(cpu_ratio, 3) + "x");
    sum_line("ms_per_scan_semantic2t_" + tag, sem2.medianOfScans(sem2.total),
             "semantic insert (2 thr) median ms/scan, range " + rangeName(r) + ": " +
                 fmt(sem2.medianOfScans(sem2.total)));
    sum_line("cpu_ms_per_scan_semantic2t_" + tag, sem2.medianOfScans(sem2.cpu),
             "semantic insert (2 thr) median CPU ms/scan (all threads), range " + rangeName(r) +
                 ": " + fmt(sem2.medianOfScans(sem2.cpu)));
    sum_line("ms_per_scan_plain_" + tag, plain.medianOfScans(plain.total),
             "plain insertPointCloud median ms/scan, range " + rangeName(r) + ": " +
                 fmt(plain.medianOfScans(plain.total)));
    const double hz = 1000.0 / sem2.medianOfScans(sem2.total);
    sum_line("hz_semantic2t_" + tag, hz,
             "semantic insert (2 thr) rate, range " + rangeName(r) + ": " + fmt(hz, 2) +
                 " Hz" + (r > 0 ? " (target >= 10)" : ""));
    const double hz_bound = 2000.0 / sem2.medianOfScans(sem2.cpu);
    sum_line("hz_bound_idle_2core_" + tag, hz_bound,
             "rate bound from CPU time, range " + rangeName(r) + ": 2 idle cores x perfect "
             "scaling = 2000 / CPU ms = " + fmt(hz_bound, 2) + " Hz");
    if (!o.quick) {
      const Series& sem1 = find("semantic", r, 1, true);
      const double hz1 = 1000.0 / sem1.medianOfScans(sem1.cpu);
      sum_line("hz_1t_cpu_" + tag, hz1,
               "1-thread semantic insert, rate from CPU time (= idle wall), range " +
                   rangeName(r) + ": " + fmt(hz1, 2) + " Hz");
      const double speedup = sem1.sum(sem1.total) / sem2.sum(sem2.total);
      sum_line("speedup_2t_vs_1t_" + tag, speedup,
               "semantic insert speed-up 2 thr vs 1 thr, range " + rangeName(r) + ": " +
                   fmt(speedup, 2) + "x");
    }
    if (o.prototype) {
      const Series& proto = find("prototype", r, 2, true);
      const double pr = proto.sum(proto.total) / plain_d.sum(plain_d.total);
      sum_line("ratio_prototype_occupancy_vs_plain_discretize_" + tag, pr,
               "bench prototype occupancy (2 thr) / plain discretize, range " + rangeName(r) + ": " +
                   fmt(pr, 3) + "x");
    }
  }
  {
    const Series& sem2 = find("semantic", -1.0, 2, true);
    for (const auto& rs : rule_series) {
      const double ratio = rs.sum(rs.total) / sem2.sum(sem2.total);
      sum_line("ratio_rule_" + rs.rule + "_vs_dempster", ratio,
               "rule " + rs.rule + " / dempster per-scan time: " + fmt(ratio, 3) + "x");
    }
  }
  sum_line("bytes_node", double(node_bytes),
           "sizeof(EvidentialOcTreeNode) = " + std::to_string(node_bytes) +
               " B, sizeof(octomap::OcTreeNode) = " + std::to_string(plain_node_bytes) + " B");
  sum_line("bytes_per_semantic_leaf", semantic_leaf_bytes,
           "bytes per semantic leaf (node + pooled payload incl. inner summaries and pool slack): " +
               fmt(semantic_leaf_bytes) + " B (target <= 16 + 4C = " + fmt(semantic_leaf_target, 0) +
               " B)");
  sum_line("peak_rss_mb_semantic", rss_sem["peak_rss_mb"],
           "peak RSS after " + std::to_string(o.scans) + " scans: semantic " +
               fmt(rss_sem["peak_rss_mb"]) + " MB, plain OcTree " + fmt(rss_plain["peak_rss_mb"]) +
               " MB");
  summary.set("peak_rss_mb_plain", rss_plain["peak_rss_mb"]);
  sum_line("ot_mb_semantic", semantic_stats.ot_bytes / 1048576.0,
           ".ot size after " + std::to_string(o.scans) + " scans: semantic " +
               fmt(semantic_stats.ot_bytes / 1048576.0, 2) + " MB, plain OcTree " +
               fmt(plain_stats.ot_bytes / 1048576.0, 2) + " MB");

  // ============================================================================================
  // JSON.
  Json root = Json::object();
  {
    Json setup = Json::object();
    setup.set("data", o.data).set("classes", o.classes).set("scans", int(scans.size()));
    setup.set("num_classes", C).set("resolution", o.resolution).set("repeats", o.repeats);
    setup.set("quick", o.quick);
    setup.set("evidence", "derived: one-hot of the predicted class, magnitude 20");
    setup.set("points_per_scan", double(find("plain", -1.0, 1, false).totalPoints()) / scans.size());
    root.set("setup", setup);
  }
  root.set("summary", summary);
  {
    Json a = Json::array();
    for (const auto& s : main_series) a.push(seriesJson(s));
    root.set("insert", a);
  }
  {
    Json a = Json::array();
    for (const auto& s : rule_series) a.push(seriesJson(s));
    root.set("rules", a);
  }
  {
    Json a = Json::array();
    for (const auto& s : phase_series) a.push(seriesJson(s));
    root.set("plain_phases", a);
  }
  {
    Json a = Json::array();
    for (const auto& row : scaling) {
      Json j = Json::object();
      j.set("points", row.points).set("plain", seriesJson(row.plain));
      j.set("semantic", seriesJson(row.semantic));
      a.push(j);
    }
    root.set("scaling_points", a);
  }
  {
    Json a = Json::array();
    for (size_t i = 0; i < publish.size(); ++i) {
      Json j = Json::object();
      j.set("scan", int(i)).set("views_ms", publish[i].views_ms).set("map_ms", publish[i].map_ms);
      j.set("occupied_voxels", publish[i].voxels).set("map_bytes", publish[i].map_bytes);
      a.push(j);
    }
    root.set("publish", a);
  }
  {
    Json m = Json::object();
    m.set("sizeof_evidential_node", node_bytes).set("sizeof_octree_node", plain_node_bytes);
    m.set("child_pointer_array_bytes", child_array);
    m.set("plain_tree_bytes_per_leaf", plain_per_leaf);
    m.set("semantic_tree_bytes_per_leaf_without_payloads", sem_tree_per_leaf);
    m.set("payload_bytes_per_slot", 4.0 * C);
    m.set("payload_pool_bytes", pool_bytes);
    m.set("pool_bytes_per_semantic_leaf", pool_per_semantic_leaf);
    m.set("bytes_per_semantic_leaf", semantic_leaf_bytes);
    m.set("semantic_leaf_target", semantic_leaf_target);
    m.set("semantic_tree", statsJson(semantic_stats));
    m.set("plain_tree", statsJson(plain_stats));
    Json rp = Json::object();
    for (const auto& [k, v] : rss_plain) rp.set(k, v);
    Json rs = Json::object();
    for (const auto& [k, v] : rss_sem) rs.set(k, v);
    m.set("rss_plain", rp).set("rss_semantic", rs);
    root.set("memory", m);
  }
  if (!o.json_path.empty()) {
    std::ofstream(o.json_path) << root.str() << "\n";
  }

  // ============================================================================================
  // Markdown.
  std::ostringstream md;
  const auto& sem_ref = find("semantic", -1.0, 2, true);
  md << "### Per-scan insert time (" << scans.size() << " scans, map growing, median of "
     << o.repeats << " run(s) per scan index; ratio = sum over the scans)\n\n";
  md << "| max range | method | threads | median wall ms/scan | points/s | wall ratio to plain | "
        "wall ratio to plain discretize | median CPU ms/scan | CPU ratio to plain | occupancy ms | "
        "kernel ms | update ms |\n";
  md << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& s : main_series) {
    const Series& plain = find("plain", s.max_range, 1, false);
    const Series& plain_d = find("plain", s.max_range, 1, true);
    const double pps = s.totalPoints() / (s.sum(s.total) / 1000.0);
    md << "| " << rangeName(s.max_range) << " | " << s.name
       << (s.kind == "semantic" ? " (" + s.rule + ")" : "") << " | " << s.threads << " | "
       << fmt(s.medianOfScans(s.total)) << " | " << fmt(pps / 1e3, 0) << " k | "
       << fmt(s.sum(s.total) / plain.sum(plain.total), 3) << " | "
       << fmt(s.sum(s.total) / plain_d.sum(plain_d.total), 3) << " | "
       << fmt(s.medianOfScans(s.cpu)) << " | " << fmt(s.sum(s.cpu) / plain.sum(plain.cpu), 3)
       << " | ";
    if (s.kind == "semantic") {
      md << fmt(s.medianOfScans(s.occupancy)) << " | " << fmt(s.medianOfScans(s.kernel)) << " | "
         << fmt(s.medianOfScans(s.update)) << " |\n";
    } else {
      md << "– | – | – |\n";
    }
  }
  md << "\nThe semantic insert runs OctoMap's ray casting with `discretize = true` (the "
        "`SemanticConfig` default), so the discretized plain OcTree is the like-for-like "
        "occupancy reference; the undiscretized one is OctoMap's default call. Plain OctoMap is "
        "the distribution's liboctomap (single-threaded).\n";

  md << "\n### Per-scan time as the map grows (range -1, ms)\n\n| scan |";
  std::vector<const Series*> growth;
  for (const auto& s : main_series)
    if (s.max_range < 0) growth.push_back(&s);
  for (const auto* s : growth)
    md << " " << (s->kind == "semantic" ? "semantic " + std::to_string(s->threads) + " thr"
                  : s->kind == "prototype" ? std::string("prototype occupancy")
                  : s->discretize ? std::string("plain discretize") : std::string("plain"))
       << " |";
  md << " semantic 2 thr: occupancy / kernel / update |\n|---|";
  for (size_t i = 0; i <= growth.size(); ++i) md << "---|";
  md << "\n";
  for (size_t i = 0; i < scans.size(); ++i) {
    md << "| " << i << " |";
    for (const auto* s : growth) md << " " << fmt(median(s->total[i])) << " |";
    md << " " << fmt(median(sem_ref.occupancy[i])) << " / " << fmt(median(sem_ref.kernel[i]))
       << " / " << fmt(median(sem_ref.update[i])) << " |\n";
  }

  md << "\n### Where the time goes (median ms/scan over the scans)\n\n| max range | what | "
        "keys / ray casting ms | kernel ms | node update ms | total ms | map equal to plain "
        "discretize |\n|---|---|---|---|---|---|---|\n";
  for (double r : ranges) {
    const Series& plain_d = find("plain", r, 1, true);
    auto same = [&](const Series& s) {
      const auto& a = s.fingerprint;
      const auto& b = plain_d.fingerprint;
      const bool eq = std::abs(a.weighted_log_odds - b.weighted_log_odds) <=
                          1e-6 * std::max(1.0, std::abs(b.weighted_log_odds)) &&
                      a.occupied_voxels == b.occupied_voxels && a.known_voxels == b.known_voxels;
      return std::string(eq ? "yes" : "NO");
    };
    for (const auto& s : phase_series) {
      if (s.max_range != r) continue;
      md << "| " << rangeName(r) << " | OctoMap insertPointCloud (discretize): computeDiscreteUpdate "
            "(KeySet) / updateNode loop | " << fmt(s.medianOfScans(s.occupancy)) << " | – | "
         << fmt(s.medianOfScans(s.update)) << " | " << fmt(s.medianOfScans(s.total)) << " | "
         << same(s) << " |\n";
    }
    const Series& sem2 = find("semantic", r, 2, true);
    md << "| " << rangeName(r) << " | semantic insert, 2 thr: InsertStats ms_occupancy (ray-key "
          "casting) / ms_kernel / ms_update (one Morton-ordered pass: occupancy, payloads, inner "
          "nodes) | "
       << fmt(sem2.medianOfScans(sem2.occupancy)) << " | " << fmt(sem2.medianOfScans(sem2.kernel))
       << " | " << fmt(sem2.medianOfScans(sem2.update)) << " | " << fmt(sem2.medianOfScans(sem2.total))
       << " | – |\n";
    if (o.prototype) {
      const Series& proto = find("prototype", r, 2, true);
      md << "| " << rangeName(r) << " | bench prototype, 2 thr: flat hash + parallel rays + Morton "
            "order / updateNode loop | " << fmt(proto.medianOfScans(proto.occupancy)) << " | – | "
         << fmt(proto.medianOfScans(proto.update)) << " | " << fmt(proto.medianOfScans(proto.total))
         << " | " << same(proto) << " |\n";
    }
  }

  md << "\n### Fusion rules (2 threads, range -1)\n\n| rule | median ms/scan | ratio to dempster | "
        "occupancy ms | kernel ms | update ms |\n|---|---|---|---|---|---|\n";
  {
    std::vector<const Series*> rules{&sem_ref};
    for (const auto& s : rule_series) rules.push_back(&s);
    for (const auto* s : rules) {
      md << "| " << s->rule << " | " << fmt(s->medianOfScans(s->total)) << " | "
         << fmt(s->sum(s->total) / sem_ref.sum(sem_ref.total), 3) << " | "
         << fmt(s->medianOfScans(s->occupancy)) << " | " << fmt(s->medianOfScans(s->kernel))
         << " | " << fmt(s->medianOfScans(s->update)) << " |\n";
    }
  }

  md << "\n### Scaling with points per scan (random subsets, first " << o.scaling_scans
     << " scans, range -1)\n\n| points/scan | plain ms/scan | semantic 2 thr ms/scan | ratio | "
        "semantic points/s | occupancy / kernel / update ms |\n|---|---|---|---|---|---|\n";
  for (const auto& row : scaling) {
    const double ratio = row.semantic.sum(row.semantic.total) / row.plain.sum(row.plain.total);
    md << "| " << row.points << " | " << fmt(row.plain.medianOfScans(row.plain.total)) << " | "
       << fmt(row.semantic.medianOfScans(row.semantic.total)) << " | " << fmt(ratio, 3) << " | "
       << fmt(row.semantic.totalPoints() / (row.semantic.sum(row.semantic.total) / 1000.0) / 1e3, 0)
       << " k | " << fmt(row.semantic.medianOfScans(row.semantic.occupancy)) << " / "
       << fmt(row.semantic.medianOfScans(row.semantic.kernel)) << " / "
       << fmt(row.semantic.medianOfScans(row.semantic.update)) << " |\n";
  }

  md << "\n### Memory (after " << scans.size() << " scans, range -1)\n\n| quantity | value |\n|---|---|\n";
  md << "| sizeof(EvidentialOcTreeNode) / sizeof(octomap::OcTreeNode) | " << node_bytes << " B / "
     << plain_node_bytes << " B |\n";
  md << "| free leaf (node only; OctoMap adds a " << int(child_array)
     << " B child array per inner node) | " << node_bytes << " B (OcTreeNode: " << plain_node_bytes
     << " B) |\n";
  md << "| tree bytes per leaf incl. inner nodes, OctoMap model: semantic tree / plain tree | "
     << fmt(sem_tree_per_leaf) << " B / " << fmt(plain_per_leaf) << " B |\n";
  md << "| semantic leaf: node + payload 4·C = " << 4 * C << " B, pooled | "
     << fmt(semantic_leaf_bytes) << " B incl. inner summaries and pool slack (target " << fmt(semantic_leaf_target, 0)
     << " B; bare: " << node_bytes + 4 * C << " B) |\n";
  md << "| semantic tree leaves: total / occupied / free / semantic / pruned / log-odds exactly 0 "
        "(kernel-created, never on a ray; OctoMap counts them occupied) | "
     << semantic_stats.leaves << " / " << semantic_stats.occupied_leaves << " / "
     << semantic_stats.free_leaves << " / " << semantic_stats.semantic_leaves << " / "
     << semantic_stats.pruned_leaves << " / " << semantic_stats.zero_log_odds_leaves << " |\n";
  md << "| plain OcTree (discretize, same rays) leaves: total / occupied / free / pruned | "
     << plain_stats.leaves << " / " << plain_stats.occupied_leaves << " / "
     << plain_stats.free_leaves << " / " << plain_stats.pruned_leaves << " |\n";
  md << "| payload slots in use: semantic leaves + inner summaries = total | "
     << semantic_stats.semantic_leaves << " + "
     << semantic_stats.semantic_nodes - std::min(semantic_stats.semantic_nodes, semantic_stats.semantic_leaves)
     << " = " << semantic_stats.semantic_nodes << " |\n";
  md << "| payload pool: reserved (capacity, incl. free list) / in use | " << fmt(pool_bytes / 1048576.0)
     << " MB / " << fmt(semantic_stats.semantic_nodes * 4.0 * C / 1048576.0) << " MB |\n";
  md << "| `memoryUsage()`: semantic tree / plain tree (discretize) | " << fmt(semantic_stats.memory_usage / 1048576.0)
     << " MB / " << fmt(plain_stats.memory_usage / 1048576.0) << " MB |\n";
  md << "| peak RSS after " << scans.size() << " scans (separate process, getrusage): semantic / plain | "
     << fmt(rss_sem["peak_rss_mb"]) << " MB / " << fmt(rss_plain["peak_rss_mb"])
     << " MB (of which scans loaded before mapping: " << fmt(rss_sem["rss_before_map_mb"]) << " MB) |\n";
  md << "| `.ot` size: semantic (saveMap) / plain discretize (OcTree::write) | "
     << fmt(semantic_stats.ot_bytes / 1048576.0, 2) << " MB / " << fmt(plain_stats.ot_bytes / 1048576.0, 2)
     << " MB |\n";
  md << "| `tree.write(stringstream)`: semantic / plain | " << fmt(semantic_stats.write_ms) << " ms / "
     << fmt(plain_stats.write_ms) << " ms |\n";

  md << "\n### Publishing cost as the map grows (semantic, 2 thr, range -1; what the ROS node "
        "builds, without ROS serialisation)\n\n| scan | occupied voxels | views (markers + cloud) ms | "
        "map message (write) ms | map bytes |\n|---|---|---|---|---|\n";
  for (size_t i = 0; i < publish.size(); ++i) {
    md << "| " << i << " | " << publish[i].voxels << " | " << fmt(publish[i].views_ms) << " | "
       << fmt(publish[i].map_ms) << " | " << publish[i].map_bytes << " |\n";
  }

  md << "\n### Summary\n\n```\n";
  for (const auto& [key, text] : summary_lines) md << text << "\n";
  md << "```\n";
  if (!o.md_path.empty()) std::ofstream(o.md_path) << md.str();

  std::cout << "==== evidential_bench summary ====\n";
  for (const auto& [key, text] : summary_lines) std::cout << text << "\n";
  return 0;
} catch (const std::exception& e) {
  std::cerr << "evidential_bench: " << e.what() << "\n";
  return 1;
}
