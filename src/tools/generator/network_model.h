// A model of a segmentation network's per-point outputs, with the failure modes of real ones.
// Per point with true class g, a difficulty
//   D = range_weight * s / s_ref                       worse with range and sparsity: s = point
//                                                       spacing (range x angular spacing), s_ref
//                                                       = 0.437 m (os1-64, 1024 columns, 50 m)
//     + border_weight * exp(-d / border_width)         near a surface of another class (d: xy
//                                                       distance, or height above the ground)
//     + rare_weight * rarity(g)                        rare and thin classes
//     + field_sigma * F(x) + object_sigma * O(object)  spatially smooth (world-fixed) and per-
//     + point_sigma * n                                object parts, and per-point noise,
// then logits
//   z_g = margin - D;  z_n = partner_gain * max(D, 0) + class_noise * eta_n   (n: the neighbour
//   class across the border, else the class's usual confusion partner);  z_c = class_noise *
//   eta_c for the others (eta: half world-fixed 1 m blocks, half per point);  void far below;
//   plus one offset shared by all classes (confidence_noise), which moves the confidence but not
//   the argmax, so confidence flags errors imperfectly.
// Consistently wrong regions: world cells of wrong_cell metres, a share wrong_rate of them (hash
// of cell and seed), in which every scan predicts the neighbour class with logit
// max(z_g, z_n) + wrong_boost: confidently and repeatably wrong.
// Outputs: logits z / temperature, probabilities softmax(z / temperature), EDL evidence
// e = evidence_scale * exp(min(z, 15)) (or softplus), predictions argmax z.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kinds.h"
#include "lidar.h"

namespace evidential_octomap::generator {

struct Scene;

struct NetworkParams {
  std::string preset = "good";
  double margin = 4.2;
  double range_weight = 1.6;
  double border_weight = 2.6;
  double border_width = 0.5;  // [m]
  double rare_weight = 1.0;
  double field_sigma = 0.7;
  double object_sigma = 0.5;
  double point_sigma = 0.7;
  double partner_gain = 0.5;
  double logit_gain = 1.7;  // scales every logit: confidence without changing the argmax
  double class_noise = 0.9;
  double confidence_noise = 0.3;
  double wrong_rate = 0.01;
  double wrong_cell = 4.0;  // [m]
  double wrong_boost = 1.5;
  double evidence_scale = 1.0;  // the factor the map is not told
  double temperature = 1.0;
  bool softplus = false;  // evidence activation: exp (default) or softplus

  // good, poor, overconfident, underconfident; throws on unknown names.
  static NetworkParams preset_named(const std::string& name);
  std::string describe() const;
};

struct NetworkOutput {
  std::vector<float> logits;       // N x C, already divided by the temperature
  std::vector<float> evidence;     // N x C
  std::vector<int> gt, predicted;  // class ids
  std::vector<uint8_t> in_wrong_cell;
};

class NetworkModel {
 public:
  NetworkModel(const NetworkParams& params, const KindClasses& classes, int num_classes,
               double angular_spacing, uint64_t seed)
      : p_(params), classes_(classes), C_(num_classes), spacing_(angular_spacing), seed_(seed) {}
  NetworkOutput run(const Scene& scene, const std::vector<LidarPoint>& points, int scan) const;
  // Whether the world cell holding (x, y, z) is one of the consistently wrong ones.
  bool wrongCell(double x, double y, double z) const;

 private:
  NetworkParams p_;
  KindClasses classes_;
  int C_;
  double spacing_;
  uint64_t seed_;
};

}  // namespace evidential_octomap::generator
