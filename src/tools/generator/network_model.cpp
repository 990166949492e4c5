#include "network_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "noise.h"
#include "rng.h"
#include "scene.h"

namespace evidential_octomap::generator {

namespace {
constexpr double kSpacingRef = 0.437;  // os1-64 at 1024 columns, 50 m
}

NetworkParams NetworkParams::preset_named(const std::string& name) {
  NetworkParams p;
  p.preset = name;
  if (name == "good") return p;
  if (name == "poor") {
    p.margin = 3.7, p.range_weight = 2.0, p.border_weight = 3.0, p.rare_weight = 1.3;
    p.field_sigma = 0.9, p.object_sigma = 0.7, p.point_sigma = 0.8, p.wrong_rate = 0.02;
    p.confidence_noise = 0.4, p.logit_gain = 1.5;
    return p;
  }
  if (name == "overconfident") {
    p.evidence_scale = 5.0, p.temperature = 0.5;
    return p;
  }
  if (name == "underconfident") {
    p.evidence_scale = 0.3, p.temperature = 2.0;
    return p;
  }
  throw std::invalid_argument("unknown network preset '" + name +
                              "' (good, poor, overconfident, underconfident)");
}

std::string NetworkParams::describe() const {
  std::ostringstream s;
  s << "preset " << preset << ": margin " << margin << ", range_weight " << range_weight
    << ", border_weight " << border_weight << ", border_width " << border_width
    << " m, rare_weight " << rare_weight << ", field_sigma " << field_sigma << ", object_sigma "
    << object_sigma << ", point_sigma " << point_sigma << ", partner_gain " << partner_gain
    << ", logit_gain " << logit_gain << ", class_noise " << class_noise << ", confidence_noise "
    << confidence_noise << ", wrong_rate " << wrong_rate << " of " << wrong_cell
    << " m cells (boost " << wrong_boost << "), evidence_scale " << evidence_scale
    << ", temperature " << temperature << ", evidence activation "
    << (softplus ? "softplus" : "exp");
  return s.str();
}

bool NetworkModel::wrongCell(double x, double y, double z) const {
  const auto cell = [&](double v) { return uint64_t(int64_t(std::floor(v / p_.wrong_cell))); };
  return unitOf(hashOf(seed_, kStreamWrongCell, cell(x), cell(y), cell(z))) < p_.wrong_rate;
}

NetworkOutput NetworkModel::run(const Scene& scene, const std::vector<LidarPoint>& points,
                                int scan) const {
  const size_t n = points.size();
  const int C = C_;
  NetworkOutput out;
  out.logits.resize(n * C);
  out.evidence.resize(n * C);
  out.gt.resize(n);
  out.predicted.resize(n);
  out.in_wrong_cell.resize(n);
  const uint64_t field_key = hashOf(seed_, kStreamNetworkField);
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; ++i) {
    const LidarPoint& pt = points[i];
    const int g = classes_.cls[int(pt.kind)];
    out.gt[i] = g;
    const uint64_t key =
        hashOf(seed_, kStreamNetwork, uint64_t(scan), uint64_t(pt.beam), uint64_t(pt.column));
    const double x = pt.p_W.x(), y = pt.p_W.y(), z = pt.p_W.z();
    // Border: the nearest other class in xy, or the ground under an object's low parts.
    int other = -1;
    double d_border = scene.borders.nearestOther(x, y, g, pt.object == 0, &other);
    if (pt.height > 2.5 && pt.kind != Kind::kBuilding) d_border = BorderMap::kCap, other = -1;
    if (pt.object != 0 && pt.height < d_border) {
      const int ground = classes_.cls[int(scene.terrain.kindAt(x, y))];
      if (ground != g && ground > 0) d_border = std::max(0.0, double(pt.height)), other = ground;
    }
    const double border = std::exp(-d_border / p_.border_width);
    const int partner =
        (other > 0 && d_border < 2.0 * p_.border_width) ? other : classes_.partner[int(pt.kind)];
    const double spacing = pt.range * spacing_ / kSpacingRef;
    const double field = 2.5 * valueNoise3(field_key, x / 3.0, y / 3.0, z / 3.0);
    const double object = normalOf(hashOf(field_key, 7, pt.object));
    const double D = p_.range_weight * spacing + p_.border_weight * border +
                     p_.rare_weight * kindInfo(pt.kind).rarity + p_.field_sigma * field +
                     p_.object_sigma * (pt.object ? object : 0.0) +
                     p_.point_sigma * normalOf(hashOf(key, 1));
    // 1 m world blocks: the part of the class noise every scan shares.
    const uint64_t block =
        hashOf(field_key, 8, uint64_t(int64_t(std::floor(x))), uint64_t(int64_t(std::floor(y))),
               uint64_t(int64_t(std::floor(z))));
    const double shared =
        p_.confidence_noise * (0.6 * normalOf(hashOf(block, 9)) + 0.8 * normalOf(hashOf(key, 2)));
    float* zl = out.logits.data() + i * C;
    for (int c = 0; c < C; ++c) {
      const double eta = 0.7071 * (normalOf(hashOf(block, 10, c)) + normalOf(hashOf(key, 3, c)));
      zl[c] = float(p_.class_noise * eta);
    }
    zl[0] = float(-4.0 + 0.5 * normalOf(hashOf(key, 4)));  // void: the net never predicts it
    if (g > 0) zl[g] = float(p_.margin - D);
    if (partner > 0 && partner != g) zl[partner] += float(p_.partner_gain * std::max(D, 0.0));
    // In a wrong cell the class's usual partner wins (not the border's: the same wrong class
    // for every point of the class in the cell, in every scan).
    const int usual = classes_.partner[int(pt.kind)];
    const bool wrong = usual > 0 && usual != g && wrongCell(x, y, z);
    out.in_wrong_cell[i] = wrong;
    if (wrong) {
      zl[usual] = std::max(zl[g], zl[partner > 0 ? partner : usual]) +
                  float(p_.wrong_boost + 0.3 * std::abs(normalOf(hashOf(key, 5))));
    }
    int arg = 0;
    for (int c = 0; c < C; ++c) {
      zl[c] = float((zl[c] + shared) * p_.logit_gain);
      if (zl[c] > zl[arg]) arg = c;
    }
    out.predicted[i] = arg;
    float* ev = out.evidence.data() + i * C;
    for (int c = 0; c < C; ++c) {
      const double v = zl[c];
      const double a =
          p_.softplus ? (v > 20.0 ? v : std::log1p(std::exp(v))) : std::exp(std::min(v, 15.0));
      ev[c] = float(p_.evidence_scale * a);
      zl[c] = float(v / p_.temperature);
    }
  }
  return out;
}

}  // namespace evidential_octomap::generator
