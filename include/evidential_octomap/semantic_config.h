// Every semantic-mapping parameter in one place, each default written once. MapSettings are what
// a stored map means (kept in its .ot header); InsertSettings say how an insert runs (not stored).
// Their names, ranges and help are listed once in settings.h, from which ROS, the CLI, Python
// and docs/parameters.md are made; they fall back to these values and never restate them.
#pragma once

#include <ostream>
#include <string>

namespace evidential_octomap {

struct MapSettings {
  // Fusion rule: "dempster" (the paper), "sbki" or "ebs".
  std::string rule = "dempster";
  // Kernel length scale l [m], kernel amplitude sigma0, adaptive-length factors beta and gamma.
  // For dempster sigma0 is each point's reliability: k <= sigma0, so even in its own voxel a
  // point keeps a vacuity of at least 1 - sigma0 and one over-confident point cannot outweigh
  // its neighbours. 0.7 was chosen across datasets (docs/results_sigma0.md; the paper's 1.0
  // lost Brier score in every leave-one-dataset-out fold).
  double length_scale = 0.3;
  double sigma0 = 0.7;
  double beta = 1.0;
  double gamma = 3.0;
  // Percentage of the most uncertain points of each scan that are dropped (psi) when the
  // threshold is on.
  double drop_percent = 10.0;
  // The paper's two uncertainty mechanisms (its Table II): the adaptive support length
  // l * beta * e^(1 - gamma u) (off: gamma = 0, support l * beta * e for every point) and the
  // per-scan percentile threshold. Both are OFF by default, chosen by measurement
  // (docs/experiments/results.md, "defaults"): on the bundled sequence each one lowers mIoU and
  // raises the Brier score with learned and knn-vote evidence (with one-hot evidence every point
  // has the same u and the threshold drops nothing). The threshold drops a scan's most uncertain
  // points, which are mostly rare-class and far points (learned evidence: bicycle and parking
  // vanish), and the adaptive length shortens exactly the supports that need neighbours' support
  // most. The uncertainty still acts: it weighs every contribution through the extended belief.
  bool adaptive_length = false;
  bool uncertainty_threshold = false;
  // The authors' released configuration: adaptive length commented out (gamma = 0, support
  // l * beta * e), count-cap down-sampling and the percentile threshold, opinions read without
  // the evidence cap by the CLI's reference_compat row. Not the paper's method; kept to set our
  // numbers beside theirs.
  bool reference_compat = false;
  // Prior alpha of S-BKI.
  float sbki_prior = 0.001f;
  // dempster: a voxel's opinion is read with its fused log-evidence sum_c L^c capped at
  // evidence_cap (all L^c scaled down in proportion; <= 0: no cap). The contributions to one
  // voxel are not independent (neighbouring points of a scan, one network over consecutive
  // scans), and without a cap Dempster's product counts them as if they were: u -> 0 and
  // p -> 1 in every well-observed voxel, right or wrong. Only the read-out changes, so the map
  // stays exact, order-independent and mergeable. 3 minimises the Brier score on the bundled
  // sequence (docs/experiments/results.md).
  // kAdaptiveCap (the default): the cap follows the evidence. The tree sets it after every
  // insert to adaptiveEvidenceCap(m), m the mean over the points it was given of a point's own
  // log-evidence sum_c log1p(e^c / C): a confident network (large m) earns a higher cap, though
  // fewer points' worth of it (about 2.71 m^0.55). The constants were chosen leave-one-dataset-
  // family-out over the bundled sequence and generated off-road sequences of four scene
  // families, network behaviours and evidence scales (docs/calibration.md); the statistic is
  // stored in the map and adds under merge, so merged maps read as sequential ones. A value >= 0
  // is a fixed cap (0: none), e.g. one fitted on labelled scans by `evidential_octomap
  // calibrate`.
  double evidence_cap = kAdaptiveCap;
  static constexpr double kAdaptiveCap = -1.0;
  // The adaptive cap of a map that has no statistic yet (payloads set by hand, or read from a
  // format without it).
  static constexpr double kCapWithoutStatistic = 3.0;
  static constexpr double kAdaptiveCapScale = 2.71, kAdaptiveCapExponent = 0.55;
  static constexpr double kMinAdaptiveCap = 1.0, kMaxAdaptiveCap = 100.0;
  static double adaptiveEvidenceCap(double mean_point_log_evidence);

  // Input down-sampling for the semantic pass (occupancy always uses every point), after the
  // percentile threshold; ds_multiplier <= 0 disables it.
  //   "average":   points and evidence averaged per cell of a grid of resolution / ds_multiplier;
  //   "count_cap": the authors' rule, at most ds_multiplier + 1 points (the first ones) per
  //                block cell of 2 x 2 x 2 voxels, which bounds the evidence a voxel gets per scan.
  // count_cap is the default (measured: higher mIoU than averaging with learned evidence, equal
  // with derived evidence, and fewer semantic points, so a faster kernel pass).
  std::string downsampling = "count_cap";
  double ds_multiplier = 5.0;
  // How far a point is from a voxel for the kernel:
  //   "voxel":  distance to the nearest point of the voxel's cube, so a point always gives its
  //             own voxel the full weight k = sigma0 (clamped to 1 by dempster);
  //   "centre": distance to the voxel centre (a short support can then miss the own voxel).
  std::string kernel_distance = "voxel";
  // The support's height as a fraction of its width, in the map frame (z up, REP 103): the
  // kernel's distance is sqrt(dx^2 + dy^2 + (dz / vertical_support)^2), so 0.5 makes the ball an
  // ellipsoid half as tall. Lower values keep a dense ground's points from spilling up onto a
  // person or a pole standing on it (and cost less), but also fill less between a vertical
  // surface's scan lines. 1 (a ball) by default, chosen across datasets: on the bundled street
  // 0.5 keeps the person class, on generated forest and rocky scenes it costs Brier score
  // (docs/experiments/results_vertical_support.md).
  double vertical_support = 1.0;
  // The same fraction for the points of ground classes (`ground: true` in the class table,
  // EvidentialOcTree::setGroundClasses): their support is flatter than other points', so a
  // road's, a trail's or a meadow's evidence stays on the ground instead of climbing a person,
  // a trunk or a rock standing on it. 0.25 by default, chosen across datasets against 1 (a
  // ball) and 0.5 (docs/experiments/results_ground_support.md). No class is ground unless the class
  // table says so, so a table without the flag keeps every support at vertical_support.
  double ground_vertical_support = 0.25;
  // Max sensor range [m] for occupancy and semantics; < 0 means unlimited.
  double max_range = -1.0;
  // Let kernel updates create leaves in unknown space (densification, S-BKI style). Created
  // leaves start at occupancy log-odds 0 (p = 0.5), which OctoMap reads as occupied. Off by
  // default: on the bundled sequence it gains little (docs/design.md) and puts phantom
  // obstacles in front of real surfaces for castRay and planners. When false only existing leaves are touched.
  bool kernel_creates_leaves = false;
  // Insert occupancy through OctoMap's discretized ray casting (one ray per hit voxel).
  bool discretize = true;
  // Semantic evidence only for voxels that are occupied before the scan or hold an end point
  // of it (a point's own voxel always gets its evidence; not exact): free space near surfaces
  // stores no semantics and is answered at query time from the surface around it
  // (EvidentialOcTree::query), and the support meets a surface in a disc instead of a ball,
  // about half the insert CPU. Which voxels get evidence depends on what was occupied before a
  // scan, so maps of one sequence in another order, or batch-mapped, differ slightly. Stored in
  // the map (format 7+), so a loaded map answers free space as the mapping one did.
  bool semantic_occupied_only = false;
};

struct InsertSettings {
  // Fast free space for live mapping (not exact): each ray's cells are walked back from its end
  // and take a shortcut after two cells already cleared by this scan's other rays, so the many
  // rays that overlap near the sensor are cast once (voxblox's "fast" integrator rule). Past the
  // shortcut a ray still clears every voxel it crosses that is occupied or holds semantics, so
  // what a mover left is cleared as in the exact mode; only free space without semantics that
  // only a shortcut ray crosses stays unobserved that scan (docs/experiments/fast_free_space.md
  // and docs/experiments/moving_objects.md measure it). An
  // insertion setting like threads: not stored in the map.
  bool fast_free_space = false;
  // Point evidence below this value counts as 0 (0: off). An evidential network's softplus or
  // exp head gives every class some evidence, nearly all of it tiny. A contribution's log-evidence
  // is below evidence_floor / C for such a class and its uncertainty u = C / S moves by at most C *
  // evidence_floor / S, while each value kept costs work in the kernel and memory in the map. 0.01
  // (1 % of one class's prior weight) makes learned evidence as cheap as one-hot
  // (docs/experiments/benchmarks.md measures cost and map quality). An insertion setting: not
  // stored.
  double evidence_floor = 0.0;
  // Moving objects leave no ghosts: each clearing observation of a voxel (a ray of a scan passes
  // through it, no ray ends in it, and it is free after the scan's misses) discounts the semantic
  // evidence it held before the scan, so that after `clearing_observations` clearings without
  // new evidence the voxel answers no class (its payload is released; a surface map,
  // semantic_occupied_only, keeps a vacuous one so that the voxel, seen empty, is not answered
  // from the surface around it). A surface that rays graze stays occupied and keeps its class;
  // the kernel evidence a scan spreads into a free voxel is kept for that scan, and a class that
  // scan's kernel row shows keeps what the voxel held (contextual discounting; the other classes
  // keep their shares: dempster L^c scaled, sbki/ebs alpha^c - prior scaled). 0: off, the
  // default: on the static points of the bundled street K = 3 raises the Brier score
  // (docs/experiments/clearing_static_cost.md, docs/long_missions.md). An insertion setting:
  // not stored in the map. Sequential mapping only: a merge of chunk maps cannot apply one
  // chunk's clearings to another chunk's evidence, so batch mapping runs with it at 0.
  int clearing_observations = 0;
  // The same for the classes a class table marks movable (ClassTable::movable, set on the tree
  // by setMovableClasses: people, vehicles), the classes that leave ghosts; it applies where it
  // is smaller than clearing_observations or that is off. 0: off.
  int movable_clearing_observations = 1;
  // Thin objects keep their class: in a voxel that this scan's points show to hold other
  // classes but not the point's own, a point's kernel weight is scaled by this (1: classes
  // ignored; 0: the support stops there). A voxel holds a class when two of its points have it,
  // or one of them and a point in a neighbouring voxel, so a lone mislabelled point does not
  // hold its voxel against the evidence around it. A voxel hit by no point of this scan, or by
  // one of the point's class, gets the full weight; a point always reaches its own voxel.
  // At 1 the many points of a road or a wall outvote the few of a person or a pole standing on
  // it. 0.75 is chosen across datasets (docs/experiments/results_other_class_weight.md); 0 stops
  // the support but makes a map over-confident where the network is wrong. An insertion setting:
  // not stored in the map.
  double other_class_weight = 0.75;
  static constexpr int kMaxClearingObservations = 1000;
  // Evidence (sum over classes of payload - prior) below which a discounted payload is released.
  static constexpr double kReleasedEvidence = 0.01;
  // The factor each clearing keeps: (kReleasedEvidence / 2 / kMaxStoredLogEvidence)^(1 / K), so
  // that K clearings bring even the largest dempster payload below kReleasedEvidence (to half of
  // it, a margin for float rounding); 1 when off (K = 0).
  static double clearingKeep(int clearings);
  // The clearings after which a class's evidence is gone (0: never): clearing_observations, or
  // movable_clearing_observations for a movable class where that comes first.
  int clearingsOf(bool movable) const;

  // Threads for the semantic pass (0 = OpenMP default).
  int threads = 0;
};

// Both halves together: what the tree keeps and the integrator reads.
struct SemanticConfig : MapSettings, InsertSettings {
  // Largest kernel support radius, in leaves, that a scan may give any point. A point's kernel
  // work grows with the cube of its support and a scan's memory with its reach
  // (docs/design.md gives a scan's measured cost at this bound and at the default).
  static constexpr double kMaxSupportLeaves = 10.0;
  // Bounds of the values a map may hold (the shared validation below).
  static constexpr double kMaxDsMultiplier = 1000.0;  // down-sampling cell >= resolution / 1000
  static constexpr int kMaxThreads = 1024;

  // The gamma that is actually used (0 without the adaptive length and under reference_compat).
  double effectiveGamma() const { return reference_compat || !adaptive_length ? 0.0 : gamma; }
  // Whether the percentile threshold is used (reference_compat forces it on).
  bool effectiveThreshold() const { return reference_compat || uncertainty_threshold; }
  // The down-sampling that is actually used (reference_compat forces "count_cap").
  const std::string& effectiveDownsampling() const;
  // Largest support length [m] these settings can give a point (u -> 0, or u = 1 when the
  // effective gamma is negative); an upper bound of what the integrator uses.
  double maxSupportLength() const;

  // The one validation of these values (the ranges of settings.h), shared by the tree's setters,
  // its file reader and writer, the ROS node's parameters and dynamic_reconfigure, and the CLI:
  // "" when every value is usable, else the first one that is not, with its allowed range.
  std::string problem() const;
  // "" when a scan with these settings is affordable in a map of leaf size `resolution`
  // (maxSupportLength() <= kMaxSupportLeaves * resolution), else what to change. Checked before
  // every scan and by the node when a setting changes; not a property of a stored map, whose
  // resolution and kernel are checked by problem() alone.
  std::string supportProblem(double resolution) const;

  void print(std::ostream& out) const;
};

}  // namespace evidential_octomap
