// evidential_bench: the performance figures of bench/README.md, measured in one run.
//
// Every method keeps its own map and the methods take turns scan by scan (the order rotated
// each scan), so a change in the shared machine's load hits them all alike:
//   - plain octomap::OcTree::insertPointCloud (discretize false, OctoMap's default call, and
//     true, the rays our integrator casts), single-threaded as the distribution ships it;
//   - EvidentialOcTree::insertSemanticScan, exact (2 threads; full run: also 1 thread and the
//     sbki / ebs rules) and with fast free space (2 threads);
// at max range -1 and 50 m. Each step records wall time, process CPU time, the calling thread's
// CPU time (the rest is the worker's: the parallel share) and the integrator's phase times.
// Then: how the fast map differs from the exact one, memory (bytes per leaf, pool slack, .ot
// size, peak RSS of separate processes that only map). Writes JSON (--json) and markdown
// (--md) and prints a summary. Wall-clock timers only; nothing here is a test.
#include <evidential_octomap/evidential_octree.h>
#include <evidential_octomap/io.h>
#include <octomap/OcTree.h>
#include <omp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_data.h"
#include "bench_methods.h"
#include "json_writer.h"
#include "occupancy_diff.h"
#include "plain_octomap.h"

using evbench::Clock;
using evbench::Json;
using evbench::liveMethod;
using evbench::median;
using evbench::Method;
using evbench::msSince;
using evbench::Phase;
using evbench::PlainMethod;
using evbench::plainMethod;
using evbench::Scan;
using evbench::SemanticMethod;
using evbench::semanticMethod;
using evidential_octomap::EvidentialOcTree;
using evidential_octomap::EvidentialOcTreeNode;
using evidential_octomap::InsertStats;
using evidential_octomap::SemanticConfig;

namespace {

struct Options {
  std::string data = "data/semantickitti_08_first10";
  std::string classes = "config/classes_semantickitti.yaml";
  int scans = 10;  // distinct scans loaded
  int steps = 0;   // inserts: 0 = scans (one pass); more = the revisit order (revisitOrder)
  double resolution = 0.2;
  int repeats = 1;
  std::vector<double> ranges = {-1.0, 50.0};  // max ranges, each its own interleaved run
  bool quick = false;                         // fewer scans and methods: under 3 minutes
  std::string json_path;
  std::string md_path;
  std::string learned_model;  // default: next to the class table (defaultLearnedModel)
  std::string rss_child;      // internal: "plain", "exact" or "fast"
  double rss_range = -1.0;
};

std::string fmt(double v, int decimals = 1) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, v);
  return buffer;
}

std::string rangeName(double r) { return r < 0 ? "-1 (unlimited)" : fmt(r, 0) + " m"; }
std::string rangeTag(double r) { return r < 0 ? "r-1" : "r" + fmt(r, 0); }

std::vector<Phase> phasesOf(size_t scans, size_t steps) {
  std::vector<Phase> phases = {{"first pass", "first", 0, std::min(scans, steps)}};
  if (steps > 10) phases.push_back({"steady state", "steady", 10, std::min<size_t>(30, steps)});
  return phases;
}

// Exact occupancy with learned evidence below 0.01 counted as 0 (SemanticConfig::evidence_floor).
std::unique_ptr<Method> flooredLearnedMethod(double range) {
  auto m = semanticMethod(range, 2, false, "dempster", true);
  m->label += ", evidence_floor 0.01";
  m->key += "_floor";
  static_cast<SemanticMethod&>(*m).config.evidence_floor = 0.01;
  return m;
}

// The methods of one max range, interleaved scan by scan.
struct RangeRun {
  double range = -1.0;
  std::vector<std::unique_ptr<Method>> methods;
  Method& get(const std::string& key) const {
    for (const auto& m : methods)
      if (m->key == key) return *m;
    throw std::logic_error("no method " + key);
  }
  const EvidentialOcTree& semanticTree(const std::string& key) const {
    return *static_cast<const SemanticMethod&>(get(key)).tree;
  }
  const octomap::OcTree& plainTree(const std::string& key) const {
    return *static_cast<const PlainMethod&>(get(key)).tree;
  }
};

RangeRun buildRun(double range, bool quick) {
  RangeRun run;
  run.range = range;
  run.methods.push_back(plainMethod(range, false));
  run.methods.push_back(plainMethod(range, true));
  run.methods.push_back(semanticMethod(range, 2, false, "dempster"));
  run.methods.push_back(semanticMethod(range, 2, true, "dempster"));
  run.methods.push_back(semanticMethod(range, 2, false, "dempster", true));
  run.methods.push_back(flooredLearnedMethod(range));
  if (range > 0) {
    run.methods.push_back(liveMethod(range, false));
    run.methods.push_back(liveMethod(range, true));
  }
  if (!quick) {
    run.methods.push_back(semanticMethod(range, 1, false, "dempster"));
    if (range < 0) {
      run.methods.push_back(semanticMethod(range, 2, false, "sbki"));
      run.methods.push_back(semanticMethod(range, 2, false, "ebs"));
    }
  }
  return run;
}

void runInterleaved(RangeRun* run, const std::vector<Scan>& scans, const std::vector<int>& order,
                    const std::vector<std::vector<float>>& evidence,
                    const std::vector<std::vector<float>>& learned, double resolution,
                    const evidential_octomap::ClassTable& classes, int repeat) {
  for (auto& m : run->methods) m->reset(resolution, classes);
  const size_t count = run->methods.size();
  for (size_t i = 0; i < order.size(); ++i) {
    const size_t scan = size_t(order[i]);
    std::cerr << "  range " << fmt(run->range, 0) << ", repeat " << repeat + 1 << ", step " << i
              << " (scan " << scan << ")" << std::endl;
    for (size_t k = 0; k < count; ++k) {
      Method& m = *run->methods[(k + i + repeat) % count];
      m.step(i, scans[scan], m.learned ? learned[scan] : evidence[scan]);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Memory of the finished maps.
struct TreeStats {
  size_t nodes = 0, leaves = 0, occupied_leaves = 0, semantic_leaves = 0;
  size_t memory_usage = 0;  // tree.memoryUsage()
  size_t memory_nodes = 0;  // OctoMap's own part (nodes + child arrays)
  double write_ms = 0.0;    // tree.write(stringstream): the map message
  size_t ot_bytes = 0;      // saveMap / OcTree::write
};

size_t fileSize(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0 ? static_cast<size_t>(st.st_size) : 0;
}

template <typename Tree, typename Save>
TreeStats treeStats(const Tree& tree, Save&& save) {
  TreeStats s;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    ++s.leaves;
    if (tree.isNodeOccupied(*it)) ++s.occupied_leaves;
  }
  s.nodes = tree.size();
  std::stringstream buffer;
  const auto start = Clock::now();
  tree.write(buffer);
  s.write_ms = msSince(start);
  const std::string path = "/tmp/evidential_bench_" + std::to_string(getpid()) + ".ot";
  save(path);
  s.ot_bytes = fileSize(path);
  std::remove(path.c_str());
  return s;
}

TreeStats semanticStats(const EvidentialOcTree& tree) {
  TreeStats s =
      treeStats(tree, [&](const std::string& p) { evidential_octomap::saveMap(tree, p); });
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    if (it->hasSemantics()) ++s.semantic_leaves;
  s.memory_usage = tree.memoryUsage();
  s.memory_nodes = tree.octomap::OccupancyOcTreeBase<EvidentialOcTreeNode>::memoryUsage();
  return s;
}

TreeStats plainStats(const octomap::OcTree& tree) {
  TreeStats s = treeStats(tree, [&](const std::string& p) { tree.write(p); });
  s.memory_usage = s.memory_nodes = tree.memoryUsage();
  return s;
}

// ---------------------------------------------------------------------------------------------
// Peak RSS of a separate process that only loads the scans and maps them.
std::string selfPath() {
  char buffer[4096];
  const ssize_t n = readlink("/proc/self/exe", buffer, sizeof(buffer) - 1);
  if (n <= 0) throw std::runtime_error("cannot read /proc/self/exe");
  buffer[n] = '\0';
  return buffer;
}

std::map<std::string, double> runRssChild(const Options& o, const std::string& mode, double range) {
  std::ostringstream cmd;
  cmd << "'" << selfPath() << "' --data '" << o.data << "' --classes '" << o.classes << "' --scans "
      << o.scans << " --resolution " << o.resolution << " --rss-child " << mode << " --rss-range "
      << range;
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
  const auto scans = evbench::loadKittiScans(o.data, o.classes, o.scans, &num_classes);
  const double before = evbench::currentRssMb();
  std::unique_ptr<Method> m =
      o.rss_child == "plain" ? plainMethod(o.rss_range, true)
                             : semanticMethod(o.rss_range, 2, o.rss_child == "fast", "dempster");
  m->reset(o.resolution, evidential_octomap::ClassTable::load(o.classes));
  for (const auto& scan : scans) {
    // The evidence of one scan at a time, as a node receives it with its cloud.
    m->insert(scan, o.rss_child == "plain" ? std::vector<float>()
                                           : evbench::derivedEvidence(scan.classes, num_classes));
  }
  std::printf("rss_after_map_mb %.3f\nrss_before_map_mb %.3f\npeak_rss_mb %.3f\n",
              evbench::currentRssMb(), before, evbench::peakRssMb());
  if (const auto* semantic = dynamic_cast<const SemanticMethod*>(m.get())) {
    const EvidentialOcTree& tree = *semantic->tree;
    const size_t pool =
        tree.memoryUsage() - tree.octomap::OccupancyOcTreeBase<EvidentialOcTreeNode>::memoryUsage();
    std::printf("memory_usage_mb %.3f\nsemantic_leaves %zu\npool_bytes_per_semantic_leaf %.2f\n",
                tree.memoryUsage() / 1048576.0, tree.numSemanticNodes(),
                double(pool) / std::max<size_t>(1, tree.numSemanticNodes()));
  }
  return 0;
}

// "-1,50" -> {-1, 50}.
std::vector<double> parseRanges(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(std::stod(item));
  if (out.empty()) throw std::invalid_argument("--ranges needs a comma-separated list");
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--data")
      o.data = next();
    else if (a == "--classes")
      o.classes = next();
    else if (a == "--scans")
      o.scans = std::stoi(next());
    else if (a == "--steps")
      o.steps = std::stoi(next());
    else if (a == "--ranges")
      o.ranges = parseRanges(next());
    else if (a == "--resolution")
      o.resolution = std::stod(next());
    else if (a == "--repeats")
      o.repeats = std::max(1, std::stoi(next()));
    else if (a == "--quick")
      o.quick = true;
    else if (a == "--json")
      o.json_path = next();
    else if (a == "--md")
      o.md_path = next();
    else if (a == "--learned-model")
      o.learned_model = next();
    else if (a == "--rss-child")
      o.rss_child = next();
    else if (a == "--rss-range")
      o.rss_range = std::stod(next());
    else if (a == "--help" || a == "-h") {
      std::cout << "evidential_bench [--data DIR] [--classes YAML] [--scans N] [--steps N]\n"
                   "  [--resolution R] [--repeats N] [--quick] [--ranges -1,50] [--json PATH] "
                   "[--md PATH]\n"
                   "  [--learned-model PATH]\n"
                   "--steps: inserts; more than --scans drives the scans forth and back at their "
                   "poses (0..9, 8..0, 1..9, ...); rows then give the first pass and the steady "
                   "state (steps 10-29)\n"
                   "--quick: 4 scans, exact, fast, learned and live at 2 threads against plain "
                   "(< 3 min)\n";
      std::exit(0);
    } else {
      throw std::invalid_argument("unknown argument " + a);
    }
  }
  if (o.quick && o.scans > 4) o.scans = 4;
  if (o.steps <= 0) o.steps = o.scans;
  return o;
}

// ---------------------------------------------------------------------------------------------
// The report: summary lines (also the JSON summary) and markdown tables.
struct Report {
  Json summary = Json::object();
  std::vector<std::string> lines;
  std::ostringstream md;
  void line(const std::string& key, double value, const std::string& text) {
    summary.set(key, value);
    lines.push_back(text);
  }
};

void insertTable(const std::vector<RangeRun>& runs, const std::vector<Phase>& phases, Report* r) {
  r->md << "### Insert time (methods interleaved scan by scan; ratios = sums over the steps of "
           "the phase)\n\n"
           "| max range | method | threads | phase | median wall ms/scan | median CPU ms/scan | "
           "CPU ratio to plain | CPU ratio to plain discretize | wall ratio to plain | parallel "
           "share of the CPU |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& run : runs) {
    const Method& plain = run.get("plain");
    const Method& plain_d = run.get("plain_discretize");
    for (const auto& m : run.methods) {
      for (const Phase& p : phases) {
        const auto cpu = Method::slice(m->cpu, p), wall = Method::slice(m->wall, p);
        r->md << "| " << rangeName(run.range) << " | " << m->label << " | " << m->threads << " | "
              << p.name << " (steps " << p.begin << "–" << p.end - 1 << ") | "
              << fmt(Method::medianOf(wall)) << " | " << fmt(Method::medianOf(cpu)) << " | "
              << fmt(Method::sum(cpu) / Method::sum(Method::slice(plain.cpu, p)), 3) << " | "
              << fmt(Method::sum(cpu) / Method::sum(Method::slice(plain_d.cpu, p)), 3) << " | "
              << fmt(Method::sum(wall) / Method::sum(Method::slice(plain.wall, p)), 3) << " | "
              << (m->threads > 1 ? fmt(100.0 * m->parallelShare(), 0) + " %" : "–") << " |\n";
      }
    }
  }
  r->md << "\nPlain OctoMap is the distribution's single-threaded liboctomap; the semantic "
           "insert casts OctoMap's discretized rays (the `SemanticConfig` default), so "
           "`discretize` is the like-for-like occupancy reference and the undiscretized call "
           "OctoMap's default. Parallel share (estimate): 2 × (process CPU − calling thread's "
           "CPU) / process CPU of the 2-thread insert, capped at 100 %; it assumes the two "
           "threads split the parallel work evenly (with dynamic scheduling the worker may take "
           "more, hence 100 %). Under `OMP_WAIT_POLICY=passive` (bench.sh) an idle worker "
           "sleeps, so its CPU is work; bench/README.md has a per-thread `perf` profile.\n";
}

void phaseTable(const std::vector<RangeRun>& runs, Report* r) {
  r->md << "\n### Per phase (median over the scans, `InsertStats`, 2 threads)\n\n"
           "| max range | method | ray casting CPU ms | kernel CPU ms | tree update CPU ms | "
           "ray casting wall ms | kernel wall ms | update wall ms |\n"
           "|---|---|---|---|---|---|---|---|\n";
  for (const auto& run : runs) {
    for (const auto& method : run.methods) {
      if (method->stats.empty() || method->stats[0].empty() || method->key.rfind("plain", 0) == 0 ||
          method->threads != 2) {
        continue;  // phases of the 2-thread semantic inserts
      }
      const Method& m = *method;
      r->md << "| " << rangeName(run.range) << " | " << m.label << " | "
            << fmt(m.medianStat(&InsertStats::cpu_ms_occupancy)) << " | "
            << fmt(m.medianStat(&InsertStats::cpu_ms_kernel)) << " | "
            << fmt(m.medianStat(&InsertStats::cpu_ms_update)) << " | "
            << fmt(m.medianStat(&InsertStats::ms_occupancy)) << " | "
            << fmt(m.medianStat(&InsertStats::ms_kernel)) << " | "
            << fmt(m.medianStat(&InsertStats::ms_update)) << " |\n";
    }
  }
}

void growthTable(const RangeRun& run, const std::vector<int>& order, Report* r) {
  r->md << "\n### Per step as the map grows (range " << rangeName(run.range)
        << ", CPU ms, first repeat)\n\n| step | scan |";
  for (const auto& m : run.methods) r->md << " " << m->key << " |";
  r->md << "\n|---|---|";
  for (size_t i = 0; i < run.methods.size(); ++i) r->md << "---|";
  r->md << "\n";
  for (size_t i = 0; i < run.methods[0]->cpu.size(); ++i) {
    r->md << "| " << i << " | " << order[i] << " |";
    for (const auto& m : run.methods) r->md << " " << fmt(m->cpu[i][0]) << " |";
    r->md << "\n";
  }
}

void diffRows(const std::string& what, const evbench::OccupancyDiff& d, double range, Report* r) {
  r->md << "| " << rangeName(range) << " | " << what << " | " << d.leaves_a << " | "
        << fmt(100.0 * d.leaves_differ / std::max<size_t>(1, d.leaves_a), 3) << " % | "
        << fmt(100.0 * d.state_differs / std::max(1.0, d.known_a), 3) << " % | "
        << fmt(100.0 * d.unknown_in_b / std::max(1.0, d.known_a), 3) << " % | "
        << fmt(100.0 * d.unknown_in_a / std::max(1.0, d.known_a), 3) << " % | "
        << fmt(100.0 * d.known_b / std::max(1.0, d.known_a), 2) << " % | "
        << fmt(100.0 * d.occupied_b / std::max(1.0, d.occupied_a), 2) << " % |\n";
}

void diffTable(const std::vector<RangeRun>& runs, Report* r) {
  r->md << "\n### Fast free space against exact (after the sequence; a = first map, b = second; "
           "volume in finest voxels)\n\n| max range | a → b | leaves of a | leaves whose "
           "occupied/free state differs or is unknown in b | volume known in both, state differs | "
           "known in a only | known in b only | known volume b / a | occupied volume b / a |\n"
           "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& run : runs) {
    const auto exact_plain =
        evbench::occupancyDiff(run.plainTree("plain_discretize"), run.semanticTree("exact"));
    diffRows("plain discretize → semantic exact", exact_plain, run.range, r);
    const auto d = evbench::occupancyDiff(run.semanticTree("exact"), run.semanticTree("fast"));
    diffRows("semantic exact → fast free space", d, run.range, r);
    const std::string tag = rangeTag(run.range);
    r->line("fast_leaves_differ_pct_" + tag,
            100.0 * d.leaves_differ / std::max<size_t>(1, d.leaves_a),
            "fast vs exact, range " + rangeName(run.range) + ": " +
                fmt(100.0 * d.leaves_differ / std::max<size_t>(1, d.leaves_a), 3) +
                " % of exact's leaves differ in occupied/free state or are unknown; known volume " +
                fmt(100.0 * d.known_b / std::max(1.0, d.known_a), 2) + " %, occupied volume " +
                fmt(100.0 * d.occupied_b / std::max(1.0, d.occupied_a), 2) + " % of exact");
    r->summary.set("fast_known_volume_pct_" + tag, 100.0 * d.known_b / std::max(1.0, d.known_a));
    r->summary.set("exact_vs_plain_state_differs_" + tag, exact_plain.state_differs);
  }
}

void memoryTable(const Options& o, const RangeRun& run, int C, Report* r) {
  std::cerr << "  memory and peak RSS (child processes)" << std::endl;
  const TreeStats sem = semanticStats(run.semanticTree("exact"));
  const TreeStats fast = semanticStats(run.semanticTree("fast"));
  const TreeStats plain = plainStats(run.plainTree("plain_discretize"));
  auto rss_plain = runRssChild(o, "plain", run.range);
  auto rss_exact = runRssChild(o, "exact", run.range);
  auto rss_fast = runRssChild(o, "fast", run.range);
  const double pool = double(sem.memory_usage - sem.memory_nodes);
  const double leaf =
      sizeof(EvidentialOcTreeNode) + pool / std::max<size_t>(1, sem.semantic_leaves);
  const double target = 16.0 + 4.0 * C;
  const double ot_ratio = double(sem.ot_bytes) / std::max<size_t>(1, plain.ot_bytes);
  r->md
      << "\n### Memory (after " << o.scans << " scans, range " << rangeName(run.range)
      << ")\n\n| quantity | semantic exact | semantic fast | plain OcTree (discretize, same rays) "
         "|\n|---|---|---|---|\n";
  r->md << "| sizeof(node) | " << sizeof(EvidentialOcTreeNode) << " B | "
        << sizeof(EvidentialOcTreeNode) << " B | " << sizeof(octomap::OcTreeNode) << " B |\n";
  r->md << "| leaves / occupied / semantic | " << sem.leaves << " / " << sem.occupied_leaves
        << " / " << sem.semantic_leaves << " | " << fast.leaves << " / " << fast.occupied_leaves
        << " / " << fast.semantic_leaves << " | " << plain.leaves << " / " << plain.occupied_leaves
        << " / – |\n";
  r->md << "| tree bytes per leaf (nodes + child arrays) | "
        << fmt(double(sem.memory_nodes) / sem.leaves) << " | "
        << fmt(double(fast.memory_nodes) / fast.leaves) << " | "
        << fmt(double(plain.memory_nodes) / plain.leaves) << " |\n";
  r->md << "| payload pool (reserved, incl. chunk slack) | " << fmt(pool / 1048576.0) << " MB | "
        << fmt((fast.memory_usage - fast.memory_nodes) / 1048576.0) << " MB | – |\n";
  r->md << "| semantic leaf: node + pool / semantic leaves (target 16 + 4·C = " << fmt(target, 0)
        << " B) | " << fmt(leaf) << " B | – | – |\n";
  r->md << "| `memoryUsage()` | " << fmt(sem.memory_usage / 1048576.0) << " MB | "
        << fmt(fast.memory_usage / 1048576.0) << " MB | " << fmt(plain.memory_usage / 1048576.0)
        << " MB |\n";
  r->md << "| peak RSS of a process that maps the scans (getrusage; the scans, loaded before "
           "mapping: "
        << fmt(rss_plain["rss_before_map_mb"]) << " MB; evidence made per scan) | "
        << fmt(rss_exact["peak_rss_mb"]) << " MB | " << fmt(rss_fast["peak_rss_mb"]) << " MB | "
        << fmt(rss_plain["peak_rss_mb"]) << " MB |\n";
  r->md << "| RSS once mapped | " << fmt(rss_exact["rss_after_map_mb"]) << " MB | "
        << fmt(rss_fast["rss_after_map_mb"]) << " MB | " << fmt(rss_plain["rss_after_map_mb"])
        << " MB |\n";
  r->md << "| `.ot` size (saveMap / OcTree::write) | " << fmt(sem.ot_bytes / 1048576.0, 2)
        << " MB | " << fmt(fast.ot_bytes / 1048576.0, 2) << " MB | "
        << fmt(plain.ot_bytes / 1048576.0, 2) << " MB |\n";
  r->md << "| `tree.write(stringstream)` (the map message) | " << fmt(sem.write_ms) << " ms | "
        << fmt(fast.write_ms) << " ms | " << fmt(plain.write_ms) << " ms |\n";
  r->line("bytes_per_semantic_leaf", leaf,
          "semantic leaf incl. pool slack: " + fmt(leaf) +
              " B (target <= 16 + 4C = " + fmt(target, 0) + " B)");
  r->line("peak_rss_mb_exact", rss_exact["peak_rss_mb"],
          "peak RSS, " + std::to_string(o.scans) + " scans: semantic exact " +
              fmt(rss_exact["peak_rss_mb"]) + " MB, fast " + fmt(rss_fast["peak_rss_mb"]) +
              " MB, plain OcTree " + fmt(rss_plain["peak_rss_mb"]) + " MB (target exact <= plain)");
  r->summary.set("peak_rss_mb_plain", rss_plain["peak_rss_mb"]);
  r->summary.set("peak_rss_mb_fast", rss_fast["peak_rss_mb"]);
  r->line("ot_ratio", ot_ratio,
          ".ot size: semantic " + fmt(sem.ot_bytes / 1048576.0, 2) + " MB / plain " +
              fmt(plain.ot_bytes / 1048576.0, 2) + " MB = " + fmt(ot_ratio, 2) + "x (target <= 2)");
}

void summaryLines(const std::vector<RangeRun>& runs, const std::vector<Phase>& phases, Report* r) {
  for (const auto& run : runs) {
    const std::string tag = rangeTag(run.range), name = rangeName(run.range);
    const Method& plain = run.get("plain");
    std::vector<std::string> keys = {"exact", "fast", "exact_learned", "exact_learned_floor"};
    if (run.range > 0) keys.insert(keys.end(), {"live", "live_learned"});
    for (const std::string& key : keys) {
      const Method& m = run.get(key);
      const double ratio = Method::sum(m.cpu) / Method::sum(plain.cpu);
      r->line("cpu_ratio_" + key + "_vs_plain_" + tag, ratio,
              key + " insert CPU / plain insertPointCloud CPU, range " + name + ": " +
                  fmt(ratio, 3) + "x" + (key.rfind("exact", 0) == 0 ? " (target <= 0.15)" : ""));
      for (const Phase& p : phases) {
        const double phase_ratio =
            Method::sum(Method::slice(m.cpu, p)) / Method::sum(Method::slice(plain.cpu, p));
        r->line("cpu_ratio_" + key + "_vs_plain_" + tag + "_" + p.tag, phase_ratio,
                key + " insert CPU / plain, range " + name + ", " + p.name + ": " +
                    fmt(phase_ratio, 3) + "x");
      }
      r->line("cpu_ms_" + key + "_" + tag, Method::medianOf(m.cpu),
              key + " median CPU ms/scan, range " + name + ": " + fmt(Method::medianOf(m.cpu)) +
                  (run.range > 0 ? " (live target <= 200)" : ""));
      r->line("wall_ms_" + key + "_" + tag, Method::medianOf(m.wall),
              key + " median wall ms/scan, range " + name + ": " + fmt(Method::medianOf(m.wall)) +
                  (run.range > 0 ? " (live target <= 100 on 2 idle cores)" : ""));
      r->line("parallel_share_" + key + "_" + tag, m.parallelShare(),
              key + " parallel share of the CPU, range " + name + ": " +
                  fmt(100.0 * m.parallelShare(), 0) + " % (target >= 80 %)");
    }
  }
}

}  // namespace

int main(int argc, char** argv) try {
  const Options o = parse(argc, argv);
  omp_set_num_threads(2);
  if (!o.rss_child.empty()) return rssChild(o);

  int num_classes = 0;
  const auto scans = evbench::loadKittiScans(o.data, o.classes, o.scans, &num_classes);
  const std::vector<int> order = evbench::revisitOrder(o.scans, o.steps);
  const std::vector<Phase> phases = phasesOf(scans.size(), order.size());
  std::vector<std::vector<float>> evidence;
  for (const auto& s : scans) evidence.push_back(evbench::derivedEvidence(s.classes, num_classes));
  // Learned (cross-fitted) evidence, computed before any timing.
  const std::string model =
      o.learned_model.empty() ? evbench::defaultLearnedModel(o.classes) : o.learned_model;
  std::vector<std::vector<float>> learned;
  for (const auto& s : scans) learned.push_back(evbench::learnedEvidence(s, model, num_classes));
  std::cerr << "loaded " << scans.size() << " scans, C = " << num_classes << ", resolution "
            << o.resolution << " m\n";

  const auto classes = evidential_octomap::ClassTable::load(o.classes);
  Report report;
  std::vector<RangeRun> runs;
  for (double range : o.ranges) {
    runs.push_back(buildRun(range, o.quick));
    for (int rep = 0; rep < o.repeats; ++rep)
      runInterleaved(&runs.back(), scans, order, evidence, learned, o.resolution, classes, rep);
  }
  insertTable(runs, phases, &report);
  phaseTable(runs, &report);
  for (const auto& run : runs) growthTable(run, order, &report);
  summaryLines(runs, phases, &report);
  diffTable(runs, &report);
  memoryTable(o, runs[0], num_classes, &report);

  report.md << "\n### Summary\n\n```\n";
  for (const auto& text : report.lines) report.md << text << "\n";
  report.md << "```\n";

  Json root = Json::object();
  Json setup = Json::object();
  setup.set("data", o.data).set("scans", int(scans.size())).set("num_classes", num_classes);
  setup.set("steps", int(order.size()));
  setup.set("resolution", o.resolution).set("repeats", o.repeats).set("quick", o.quick);
  setup.set("evidence",
            "derived: one-hot of the predicted class, magnitude 20; *_learned methods: "
            "learned (cross-fitted), " +
                model);
  setup.set("points_per_scan", double(scans[0].points_W.size()));
  root.set("setup", setup).set("summary", report.summary);
  Json methods = Json::array();
  for (const auto& run : runs) {
    for (const auto& m : run.methods) {
      Json j = Json::object();
      j.set("key", m->key).set("label", m->label).set("max_range", run.range);
      j.set("threads", m->threads).set("cpu_ms_total", Method::sum(m->cpu));
      j.set("wall_ms_total", Method::sum(m->wall))
          .set("main_thread_cpu_ms_total", Method::sum(m->main_cpu));
      j.set("cpu_ms_median", Method::medianOf(m->cpu))
          .set("wall_ms_median", Method::medianOf(m->wall));
      j.set("cpu_ms_occupancy", m->sumStat(&InsertStats::cpu_ms_occupancy));
      j.set("cpu_ms_kernel", m->sumStat(&InsertStats::cpu_ms_kernel));
      j.set("cpu_ms_update", m->sumStat(&InsertStats::cpu_ms_update));
      Json per_step = Json::array();
      for (const auto& c : m->cpu) per_step.push(c.empty() ? 0.0 : c[0]);
      j.set("cpu_ms_per_step", per_step);
      methods.push(j);
    }
  }
  root.set("methods", methods);
  if (!o.json_path.empty()) std::ofstream(o.json_path) << root.str() << "\n";
  if (!o.md_path.empty()) std::ofstream(o.md_path) << report.md.str();
  std::cout << "==== evidential_bench summary ====\n";
  for (const auto& text : report.lines) std::cout << text << "\n";
  return 0;
} catch (const std::exception& e) {
  std::cerr << "evidential_bench: " << e.what() << "\n";
  return 1;
}
