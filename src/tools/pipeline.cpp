#include "pipeline.h"

#include "evidential_octomap/local_map.h"
#include "evidential_octomap/io.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <numeric>
#include <stdexcept>

#include "evidence_calibration.h"
#include "progress_bar.h"

namespace evidential_octomap::tools {

std::string useSyntheticPredictions(std::vector<Scan>* scans, const ClassTable& classes,
                                    const NoiseModel& noise) {
  for (Scan& s : *scans) {
    s.predicted =
        syntheticPredictions(s.points_S, s.gt, classes.numClasses(), classes.ignore_class, noise);
  }
  return noise.describe();
}

Protocol makeProtocol(const std::string& name, size_t num_scans) {
  Protocol p;
  p.name = name;
  if (name == "reconstruction") {
    for (size_t i = 0; i < num_scans; ++i) p.map_scans.push_back(i);
    p.query_scans = p.map_scans;
  } else if (name == "held-out") {
    if (num_scans < 2) throw std::invalid_argument("held-out protocol needs at least 2 scans");
    const size_t half = num_scans / 2;
    for (size_t i = 0; i < num_scans; ++i) (i < half ? p.map_scans : p.query_scans).push_back(i);
  } else {
    throw std::invalid_argument("unknown protocol '" + name +
                                "' (valid: reconstruction, held-out)");
  }
  return p;
}

std::vector<Scan> loadScans(const Dataset& dataset, size_t limit, bool progress) {
  const size_t n = limit == 0 ? dataset.size() : std::min(limit, dataset.size());
  std::vector<Scan> scans;
  scans.reserve(n);
  ProgressBar bar(n, "loading", "scan", progress ? -1 : 0);
  for (size_t i = 0; i < n; ++i) {
    scans.push_back(dataset.load(i));
    bar.tick();
  }
  return scans;
}

std::vector<Query> buildQueries(const std::vector<Scan>& scans, const std::vector<size_t>& which,
                                int ignore_class, const std::vector<std::vector<float>>* evidence,
                                std::vector<float>* query_evidence) {
  std::vector<Query> queries;
  for (size_t s : which) {
    const Scan& scan = scans.at(s);
    if (scan.gt.size() != scan.size()) {
      throw std::runtime_error("scan " + scan.name + " has no ground-truth labels to query");
    }
    const bool has_pred = scan.predicted.size() == scan.size();
    const float* e = nullptr;
    size_t num_classes = 0;
    if (evidence && query_evidence) {
      e = evidence->at(s).data();
      num_classes = evidence->at(s).size() / std::max<size_t>(1, scan.size());
    }
    for (size_t i = 0; i < scan.size(); ++i) {
      if (scan.gt[i] < 0 || scan.gt[i] == ignore_class) continue;
      const Eigen::Vector3f p = scan.pointW(i);
      queries.push_back(
          {octomap::point3d(p.x(), p.y(), p.z()), scan.gt[i], has_pred ? scan.predicted[i] : -1});
      if (e)
        query_evidence->insert(query_evidence->end(), e + i * num_classes,
                               e + (i + 1) * num_classes);
    }
  }
  return queries;
}

std::vector<octomap::OcTreeKey> endpointKeys(const std::vector<Scan>& scans,
                                             const std::vector<size_t>& which, double resolution) {
  const octomap::OcTree keys_of(resolution);  // only for coordToKeyChecked
  std::vector<octomap::OcTreeKey> keys;
  for (size_t s : which) {
    const Scan& scan = scans.at(s);
    for (size_t i = 0; i < scan.size(); ++i) {
      const Eigen::Vector3f p = scan.pointW(i);
      octomap::OcTreeKey key;
      if (keys_of.coordToKeyChecked(octomap::point3d(p.x(), p.y(), p.z()), key))
        keys.push_back(key);
    }
  }
  return keys;
}

std::vector<std::vector<float>> deriveEvidenceFor(const std::vector<Scan>& scans,
                                                  const std::vector<size_t>& which,
                                                  const EvidenceOptions& options,
                                                  const ClassTable& classes,
                                                  const std::vector<size_t>& also) {
  const int C = classes.numClasses();
  ConfusionModel model(C, classes.ignore_class);
  if (options.source == EvidenceSource::kConfusion) {
    for (size_t s : which) {
      const Scan& scan = scans.at(s);
      if (scan.gt.size() != scan.size() || scan.predicted.size() != scan.size()) {
        throw std::runtime_error("confusion evidence needs GT and predictions, scan " + scan.name +
                                 " lacks one");
      }
      model.addScan(s, scan.gt, scan.predicted);
    }
  }
  std::unique_ptr<LearnedEvidenceModel> learned;
  if (options.source == EvidenceSource::kLearned) {
    learned =
        std::make_unique<LearnedEvidenceModel>(LearnedEvidenceModel::load(options.learned_model));
  }
  std::vector<std::vector<float>> evidence(scans.size());
  for (size_t s : which) {
    evidence[s] = deriveEvidence(scans.at(s), s, options, C, &model, learned.get());
  }
  for (size_t s : also) {
    if (evidence[s].empty()) {
      evidence[s] = deriveEvidence(scans.at(s), s, options, C, &model, learned.get());
    }
  }
  if (options.calibrate && derivedFromHardLabels(options.source)) {
    EvidenceCalibration calibration(C, classes.ignore_class);
    for (size_t s : which) {
      if (scans.at(s).gt.size() != scans.at(s).size()) {
        throw std::runtime_error(
            "calibrating derived evidence needs GT labels of the mapping "
            "scans, scan " +
            scans.at(s).name +
            " has none (use "
            "--no-calibration)");
      }
      calibration.addScan(s, evidence[s], scans.at(s).gt);
    }
    for (size_t s = 0; s < scans.size(); ++s) {
      if (!evidence[s].empty()) calibration.apply(s, &evidence[s]);
    }
  }
  return evidence;
}

double MapRun::ms_median() const {
  if (ms_per_scan.empty()) return 0.0;
  std::vector<double> v = ms_per_scan;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double MapRun::ms_mean() const {
  if (ms_per_scan.empty()) return 0.0;
  return std::accumulate(ms_per_scan.begin(), ms_per_scan.end(), 0.0) / ms_per_scan.size();
}

MapRun runMapping(const std::vector<Scan>& scans, const std::vector<size_t>& which,
                  const std::vector<std::vector<float>>& evidence, const ClassTable& classes,
                  const SemanticConfig& config, double resolution, bool progress,
                  const std::string& label, const Autosave& autosave,
                  const LocalMapOptions& local_map) {
  MapRun run;
  run.tree = std::make_unique<EvidentialOcTree>(resolution, classes.numClasses(), config);
  run.tree->setClasses(classes);
  std::unique_ptr<LocalMap> local;
  if (local_map.radius > 0.0) {
    local = std::make_unique<LocalMap>(run.tree.get(), local_map.tile_directory, local_map.radius);
  }
  ProgressBar bar(which.size(), label, "scan", progress ? -1 : 0);
  for (size_t s : which) {
    const Scan& scan = scans.at(s);
    const octomap::Pointcloud points_W = scan.pointsW();
    const Eigen::Vector3d o = scan.originW();
    const octomap::point3d origin(float(o.x()), float(o.y()), float(o.z()));
    const auto t0 = std::chrono::steady_clock::now();
    const InsertStats st = local ? local->insertSemanticScan(points_W, evidence.at(s), origin)
                                 : run.tree->insertSemanticScan(points_W, evidence.at(s), origin);
    const auto t1 = std::chrono::steady_clock::now();
    run.ms_per_scan.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    InsertStats& t = run.total;
    t.points_in += st.points_in;
    t.points_skipped += st.points_skipped;
    t.points_beyond_range += st.points_beyond_range;
    t.semantic_points += st.semantic_points;
    t.points_dropped_uncertain += st.points_dropped_uncertain;
    t.uncertainty_threshold = st.uncertainty_threshold;
    t.voxels_updated += st.voxels_updated;
    t.ms_occupancy += st.ms_occupancy;
    t.ms_kernel += st.ms_kernel;
    t.ms_update += st.ms_update;
    t.cpu_ms_occupancy += st.cpu_ms_occupancy;
    t.cpu_ms_kernel += st.cpu_ms_kernel;
    t.cpu_ms_update += st.cpu_ms_update;
    ++run.scans_mapped;
    if (autosave.every > 0 && run.scans_mapped % autosave.every == 0) {
      saveMap(local ? *local->globalMap() : *run.tree, autosave.path);
    }
    bar.tick();
  }
  if (local) run.tree = local->globalMap();
  return run;
}

}  // namespace evidential_octomap::tools
