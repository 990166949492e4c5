// evidential_sequence_bench: CPU and wall time of every insert over a long or revisiting
// sequence, scan by scan, for plain OctoMap, the exact semantic insert (library defaults) and
// the live launch's settings, interleaved in one process (plain first, the others' order
// shuffled each step) so a change of the shared machine's load hits them alike. Writes one CSV
// row per (step, method); bench/sequence_report.py turns the rows into the tables and the
// per-scan plot.
//
//   evidential_sequence_bench --data DIR --classes YAML --order revisit --scans 10 --steps 60
//   evidential_sequence_bench --data out/long --classes out/long/classes.yaml --order forward
//   evidential_sequence_bench ... --only exact   # one method alone: its RSS after every step
//   evidential_sequence_bench ... --methods plain,exact,occupied_only
//   evidential_sequence_bench ... --methods plain,live,live_fast_free_space
//   evidential_sequence_bench ... --methods plain,exact,exact_no_clearing,live,live_no_clearing
//   evidential_sequence_bench ... --methods plain,live,live:ds_multiplier=1:length_scale=0.15
//   evidential_sequence_bench ... --only local --radius 60 --tile-dir out/tiles --save out/g.ot
//     (local: the exact insert in a LocalMap; --save writes the method's whole map at the end,
//      for exact the map, for local the global map merged from the tiles, both fully pruned)
//
// Evidence is derived: one-hot of the predicted class x 20. Timers only; nothing here is a test.
#include <evidential_octomap/detail/tree_editing.h>
#include <evidential_octomap/evidential_octree.h>
#include <evidential_octomap/io.h>
#include <evidential_octomap/local_map.h>
#include <evidential_octomap/settings.h>
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <random>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_data.h"
#include "bench_methods.h"

namespace {

struct Options {
  std::string data, classes, csv = "sequence.csv", order = "revisit", only, tile_dir, save;
  std::string methods = "plain,exact,live";  // interleaved; --only: one alone (its own RSS)
  int scans = 0;   // revisit: distinct scans (0: 10); forward: the first N (0: every scan)
  int steps = 60;  // revisit only
  double range = 50.0, resolution = 0.2;
  double radius = 0.0;  // local: the LocalMap radius (0: the reach of a scan)
};

Options parse(int argc, char** argv) {
  Options o;
  // Every option takes a value: the table says where it goes.
  const std::map<std::string, std::function<void(const std::string&)>> options = {
      {"--data", [&](const std::string& v) { o.data = v; }},
      {"--classes", [&](const std::string& v) { o.classes = v; }},
      {"--csv", [&](const std::string& v) { o.csv = v; }},
      {"--order", [&](const std::string& v) { o.order = v; }},
      {"--only", [&](const std::string& v) { o.only = v; }},
      {"--tile-dir", [&](const std::string& v) { o.tile_dir = v; }},
      {"--save", [&](const std::string& v) { o.save = v; }},
      {"--radius", [&](const std::string& v) { o.radius = std::stod(v); }},
      {"--methods", [&](const std::string& v) { o.methods = v; }},
      {"--scans", [&](const std::string& v) { o.scans = std::stoi(v); }},
      {"--steps", [&](const std::string& v) { o.steps = std::stoi(v); }},
      {"--range", [&](const std::string& v) { o.range = std::stod(v); }},
      {"--resolution", [&](const std::string& v) { o.resolution = std::stod(v); }}};
  for (int i = 1; i < argc; i += 2) {
    const auto option = options.find(argv[i]);
    if (option == options.end())
      throw std::invalid_argument(std::string("unknown argument ") + argv[i] +
                                  " (see the top of sequence_bench.cpp)");
    if (i + 1 >= argc) throw std::invalid_argument(std::string(argv[i]) + " needs a value");
    option->second(argv[i + 1]);
  }
  if (o.data.empty() || o.classes.empty())
    throw std::invalid_argument("--data and --classes needed");
  if (o.order != "revisit" && o.order != "forward")
    throw std::invalid_argument("--order is revisit or forward");
  return o;
}

// The exact insert with semantic evidence only in occupied voxels (semantic_occupied_only): how
// cheap fewer kernel rows make it (a different map).
std::unique_ptr<evbench::Method> occupiedOnlyMethod(double range) {
  auto m = evbench::semanticMethod(range, 2, false, "dempster");
  m->key = "occupied_only";
  m->label = "semantic insert, exact, semantic_occupied_only";
  static_cast<evbench::SemanticMethod&>(*m).config.semantic_occupied_only = true;
  return m;
}

// The live launch's settings with semantic evidence in free space too (what the launch set
// before it kept evidence on the surface).
std::unique_ptr<evbench::Method> liveVolumeMethod(double range) {
  auto m = evbench::liveMethod(range, false);
  m->key = "live_volume";
  m->label = "live launch settings without semantic_occupied_only";
  static_cast<evbench::SemanticMethod&>(*m).config.semantic_occupied_only = false;
  return m;
}

// The live launch's settings with the rays' shortcut through cleared space (fast_free_space).
std::unique_ptr<evbench::Method> liveFastFreeSpaceMethod(double range) {
  auto m = evbench::liveMethod(range, false);
  m->key = "live_fast_free_space";
  m->label = "live launch settings with fast_free_space";
  static_cast<evbench::SemanticMethod&>(*m).config.fast_free_space = true;
  return m;
}

// A method without the default clearing of movable classes (movable_clearing_observations 0).
std::unique_ptr<evbench::Method> withoutClearing(std::unique_ptr<evbench::Method> m) {
  m->key += "_no_clearing";
  m->label += ", movable_clearing_observations 0";
  static_cast<evbench::SemanticMethod&>(*m).config.movable_clearing_observations = 0;
  return m;
}

// The exact insert in a map that keeps only the region around the sensor in memory.
struct LocalMethod : evbench::SemanticMethod {
  std::string tile_dir;
  double radius = 0.0;
  std::unique_ptr<evidential_octomap::LocalMap> local;
  void reset(double resolution, const evidential_octomap::ClassTable& classes) override {
    SemanticMethod::reset(resolution, classes);
    const double r = radius > 0.0 ? radius : evidential_octomap::LocalMap::reach(*tree);
    local = std::make_unique<evidential_octomap::LocalMap>(tree.get(), tile_dir, r);
  }
  evbench::InsertStats insert(const evbench::Scan& scan, const std::vector<float>& evidence) override {
    return local->insertSemanticScan(scan.points_W, evidence, scan.origin_W);
  }
};

std::unique_ptr<evbench::Method> localMethod(const Options& o) {
  if (o.tile_dir.empty()) throw std::invalid_argument("--only local needs --tile-dir");
  auto m = std::make_unique<LocalMethod>();
  m->key = "local";
  m->label = "semantic insert, exact, local map (tiles on disk)";
  m->max_range = o.range;
  m->threads = 2;
  m->tile_dir = o.tile_dir;
  m->radius = o.radius;
  return m;
}

// The method's whole map, fully pruned, to `path` (a plain map is not written).
void saveWholeMap(evbench::Method& m, const std::string& path) {
  std::unique_ptr<evbench::EvidentialOcTree> global;
  evbench::EvidentialOcTree* map = nullptr;
  if (auto* local = dynamic_cast<LocalMethod*>(&m)) {
    global = local->local->globalMap();
    map = global.get();
  } else if (auto* semantic = dynamic_cast<evbench::SemanticMethod*>(&m)) {
    map = semantic->tree.get();
  }
  if (!map) return;
  evidential_octomap::detail::TreeEditing::updateInnerNodes(*map);
  evidential_octomap::saveMap(*map, path);
}

// A method's settings changed: `spec` is its key, then `:name=value` per setting of the core's
// list (as the CLI's compare variants), e.g. live:ds_multiplier=1:length_scale=0.15.
std::unique_ptr<evbench::Method> withSettings(std::unique_ptr<evbench::Method> m,
                                              const std::string& spec) {
  auto& config = static_cast<evbench::SemanticMethod&>(*m).config;
  std::stringstream in(spec.substr(spec.find(':') + 1));
  std::string item;
  while (std::getline(in, item, ':')) {
    const size_t eq = item.find('=');
    const evidential_octomap::Setting* setting =
        evidential_octomap::findSetting(item.substr(0, eq));
    if (eq == std::string::npos || !setting || !setting->parse(item.substr(eq + 1), &config))
      throw std::invalid_argument("not a setting=value: " + item + " (in " + spec + ")");
  }
  const std::string problem = config.problem();
  if (!problem.empty()) throw std::invalid_argument(spec + ": " + problem);
  m->key = spec;
  m->label += " with " + spec.substr(spec.find(':') + 1);
  return m;
}

// The methods named in `list` (comma-separated keys), in that order.
std::vector<std::unique_ptr<evbench::Method>> methodsOf(const Options& o) {
  std::vector<std::unique_ptr<evbench::Method>> out;
  std::stringstream in(o.only.empty() ? o.methods : o.only);
  std::string key;
  while (std::getline(in, key, ',')) {
    if (key == "plain")
      out.push_back(evbench::plainMethod(o.range, false));
    else if (key == "exact")
      out.push_back(evbench::semanticMethod(o.range, 2, false, "dempster"));
    else if (key == "live")
      out.push_back(evbench::liveMethod(o.range, false));
    else if (key == "exact_no_clearing")
      out.push_back(withoutClearing(evbench::semanticMethod(o.range, 2, false, "dempster")));
    else if (key == "live_no_clearing")
      out.push_back(withoutClearing(evbench::liveMethod(o.range, false)));
    else if (key == "occupied_only")
      out.push_back(occupiedOnlyMethod(o.range));
    else if (key == "live_volume")
      out.push_back(liveVolumeMethod(o.range));
    else if (key == "live_fast_free_space")
      out.push_back(liveFastFreeSpaceMethod(o.range));
    else if (key == "local")
      out.push_back(localMethod(o));
    else if (key.rfind("live:", 0) == 0)
      out.push_back(withSettings(evbench::liveMethod(o.range, false), key));
    else if (key.rfind("exact:", 0) == 0)
      out.push_back(withSettings(evbench::semanticMethod(o.range, 2, false, "dempster"), key));
    else
      throw std::invalid_argument("methods are plain, exact, live, live_fast_free_space, "
                                  "occupied_only, live_volume, local, live:SETTING=VALUE..., "
                                  "exact:SETTING=VALUE...: " + key);
  }
  return out;
}

// The order of the methods' turns at step i: plain OctoMap first, the others shuffled (a
// fixed seed per step). Plain's hash set of every ray cell leaves the caches cold, and a method
// also pays for the one before it, so in a fixed order the method right after plain paid about
// 4 % of the exact insert, 15 % of the live one; shuffled, each follows each equally often.
std::vector<size_t> turns(size_t step,
                          const std::vector<std::unique_ptr<evbench::Method>>& methods) {
  std::vector<size_t> order, others;
  for (size_t k = 0; k < methods.size(); ++k)
    (methods[k]->key == "plain" ? order : others).push_back(k);
  std::mt19937 random(static_cast<uint32_t>(step));
  std::shuffle(others.begin(), others.end(), random);
  order.insert(order.end(), others.begin(), others.end());
  return order;
}

// Scans by index: the revisit keeps its few distinct scans, a forward run loads each once.
class ScanSource {
 public:
  explicit ScanSource(const Options& o)
      : sequence_(o.data, o.classes), revisit_(o.order == "revisit") {
    if (revisit_) {
      const int n = o.scans > 0 ? o.scans : 10;
      for (int i = 0; i < n; ++i) cache_.push_back(sequence_.load(i));
      order_ = evbench::revisitOrder(n, o.steps);
    } else {
      const int n =
          o.scans > 0 ? std::min<int>(o.scans, int(sequence_.size())) : int(sequence_.size());
      for (int i = 0; i < n; ++i) order_.push_back(i);
    }
  }
  const std::vector<int>& order() const { return order_; }
  int numClasses() const { return sequence_.numClasses(); }
  evbench::Scan get(int i) const { return revisit_ ? cache_[size_t(i)] : sequence_.load(i); }

 private:
  evbench::KittiSequence sequence_;
  bool revisit_;
  std::vector<evbench::Scan> cache_;
  std::vector<int> order_;
};

}  // namespace

int main(int argc, char** argv) try {
  const Options o = parse(argc, argv);
  omp_set_num_threads(2);
  const ScanSource source(o);
  auto methods = methodsOf(o);  // --only: the one method alone, for its RSS
  const int C = source.numClasses();
  const auto classes = evidential_octomap::ClassTable::load(o.classes);
  for (auto& m : methods) m->reset(o.resolution, classes);
  std::ofstream csv(o.csv);
  if (!csv) throw std::runtime_error("cannot write " + o.csv);
  csv << "step,scan,method,cpu_ms,wall_ms,cpu_ms_rays,cpu_ms_kernel,cpu_ms_update,rss_mb,"
         "peak_rss_mb,wall_ms_rays,wall_ms_kernel,wall_ms_update\n";
  const auto& order = source.order();
  for (size_t i = 0; i < order.size(); ++i) {
    const evbench::Scan scan = source.get(order[i]);
    const std::vector<float> evidence = evbench::derivedEvidence(scan.classes, C);
    for (const size_t k : turns(i, methods)) {
      evbench::Method& m = *methods[k];
      m.step(i, scan, evidence);
      const auto& s = m.stats[i].back();
      csv << i << "," << order[i] << "," << m.key << "," << m.cpu[i].back() << ","
          << m.wall[i].back() << "," << s.cpu_ms_occupancy << "," << s.cpu_ms_kernel << ","
          << s.cpu_ms_update << "," << evbench::currentRssMb() << "," << evbench::peakRssMb()
          << "," << s.ms_occupancy << "," << s.ms_kernel << "," << s.ms_update << "\n";
    }
    csv.flush();
    if (i % 10 == 0) std::cerr << "  step " << i << " / " << order.size() << std::endl;
  }
  if (!o.save.empty()) saveWholeMap(*methods.front(), o.save);
  return 0;
} catch (const std::exception& e) {
  std::cerr << "evidential_sequence_bench: " << e.what() << "\n";
  return 1;
}
