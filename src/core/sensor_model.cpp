#include "evidential_octomap/sensor_model.h"

#include <octomap/octomap_utils.h>

#include <sstream>

namespace evidential_octomap {
namespace {

// OctoMap's setters store (float) logodds(p); a monotone map, so bounds compare the same way.
float logOdds(double probability) { return static_cast<float>(octomap::logodds(probability)); }

std::string outside(const char* name, double probability, double lo, double hi) {
  std::ostringstream s;
  s << "sensor model: " << name << " = " << probability << " must lie in [" << lo << ", " << hi
    << "] (finite log-odds, not inverted)";
  return s.str();
}

}  // namespace

std::string SensorModel::problemOfLogOdds(float hit_log, float miss_log, float clamp_min_log,
                                          float clamp_max_log, float threshold_log) {
  struct Check {
    const char* name;
    float value;
    double lo, hi;
  };
  const Check checks[] = {{"hit", hit_log, kMinHit, kMaxHit},
                          {"miss", miss_log, kMinMiss, kMaxMiss},
                          {"clamp_min", clamp_min_log, kMinClampMin, kMaxClampMin},
                          {"clamp_max", clamp_max_log, kMinClampMax, kMaxClampMax},
                          {"occupancy_threshold", threshold_log, kMinProbability, kMaxProbability}};
  for (const Check& c : checks) {
    if (!(c.value >= logOdds(c.lo) && c.value <= logOdds(c.hi))) {  // NaN fails too
      return outside(c.name, octomap::probability(c.value), c.lo, c.hi);
    }
  }
  if (!(clamp_min_log < clamp_max_log)) {
    std::ostringstream s;
    s << "sensor model: clamp_min = " << octomap::probability(clamp_min_log)
      << " must be below clamp_max = " << octomap::probability(clamp_max_log);
    return s.str();
  }
  return "";
}

std::string SensorModel::problem() const {
  // Checked as the tree stores them, (float) log-odds: a model read back from a tree (whose
  // probabilities went through that float) passes exactly when the one that was set did.
  return problemOfLogOdds(logOdds(hit), logOdds(miss), logOdds(clamp_min), logOdds(clamp_max),
                          logOdds(occupancy_threshold));
}

}  // namespace evidential_octomap
