// Paired spatial-block bootstrap of mIoU(all) and Brier differences (paired_bootstrap.h).
#include "evidential_octomap/evaluation/paired_bootstrap.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <unordered_map>

namespace evidential_octomap {

std::vector<uint32_t> spatialBlocks(const std::vector<Query>& queries, double block_size,
                                    size_t* blocks) {
  if (!(block_size > 0.0)) throw std::invalid_argument("spatialBlocks: block_size must be > 0");
  std::unordered_map<uint64_t, uint32_t> id;
  std::vector<uint32_t> block(queries.size());
  for (size_t i = 0; i < queries.size(); ++i) {
    const int64_t x = int64_t(std::floor(queries[i].point_W.x() / block_size));
    const int64_t y = int64_t(std::floor(queries[i].point_W.y() / block_size));
    // Shifted as unsigned: a left shift of a negative int64 is undefined (UBSan, x < 0).
    const uint64_t key = (uint64_t(x) << 32) ^ (uint64_t(y) & 0xffffffffu);
    block[i] = id.emplace(key, uint32_t(id.size())).first->second;
  }
  if (blocks != nullptr) *blocks = id.size();
  return block;
}

BlockScores::BlockScores(int num_classes, const std::vector<uint32_t>& block_of_query,
                         size_t blocks, const std::vector<QueryOutcome>& outcomes)
    : num_classes_(num_classes), blocks_(blocks) {
  if (block_of_query.size() != outcomes.size()) {
    throw std::invalid_argument("BlockScores: one block index per outcome expected");
  }
  std::vector<std::map<std::pair<int16_t, int16_t>, uint32_t>> cells(blocks);
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const QueryOutcome& o = outcomes[i];
    if (o.gt < 0) continue;  // not counted
    const uint32_t b = block_of_query.at(i);
    ++cells.at(b)[{o.gt, o.label}];
    blocks_[b].brier_sum += o.brier;
    ++blocks_[b].queries;
  }
  for (size_t b = 0; b < blocks; ++b) {
    for (const auto& [key, count] : cells[b])
      blocks_[b].cells.push_back({key.first, key.second, count});
  }
}

double BlockScores::miouAll(const std::vector<uint32_t>& weight, int ignore_class) const {
  ConfusionMatrix m(num_classes_);
  for (size_t b = 0; b < blocks_.size(); ++b) {
    if (weight[b] == 0) continue;
    for (const Cell& c : blocks_[b].cells) m.add(c.gt, c.label, uint64_t(c.count) * weight[b]);
  }
  return m.meanIou(ignore_class);
}

double BlockScores::brier(const std::vector<uint32_t>& weight) const {
  double sum = 0.0, n = 0.0;
  for (size_t b = 0; b < blocks_.size(); ++b) {
    sum += weight[b] * blocks_[b].brier_sum;
    n += weight[b] * double(blocks_[b].queries);
  }
  return n > 0.0 ? sum / n : std::nan("");
}

namespace {
BootstrapInterval percentileInterval(double estimate, std::vector<double> replicates,
                                     double alpha) {
  BootstrapInterval out;
  out.estimate = estimate;
  replicates.erase(
      std::remove_if(replicates.begin(), replicates.end(), [](double v) { return std::isnan(v); }),
      replicates.end());
  if (replicates.empty()) {
    out.lower = out.upper = out.share_positive = std::nan("");
    return out;
  }
  std::sort(replicates.begin(), replicates.end());
  const double last = double(replicates.size() - 1);
  out.lower = replicates[size_t(std::floor(alpha / 2.0 * last))];
  out.upper = replicates[size_t(std::ceil((1.0 - alpha / 2.0) * last))];
  const auto positive =
      std::count_if(replicates.begin(), replicates.end(), [](double v) { return v > 0.0; });
  out.share_positive = double(positive) / double(replicates.size());
  return out;
}
}  // namespace

PairedDifference pairedBootstrap(const BlockScores& row, const BlockScores& reference,
                                 int ignore_class, const BootstrapSettings& settings) {
  if (row.numClasses() != reference.numClasses() || row.blocks() != reference.blocks()) {
    throw std::invalid_argument("pairedBootstrap: rows of different classes or blocks");
  }
  if (settings.replicates < 1) throw std::invalid_argument("pairedBootstrap: replicates < 1");
  const size_t k = row.blocks();
  PairedDifference d;
  d.blocks = k;
  d.settings = settings;
  const std::vector<uint32_t> ones(k, 1);
  const double miou = row.miouAll(ones, ignore_class) - reference.miouAll(ones, ignore_class);
  const double brier = row.brier(ones) - reference.brier(ones);
  std::mt19937_64 rng(settings.seed);
  std::uniform_int_distribution<size_t> pick(0, k ? k - 1 : 0);
  std::vector<double> miou_r, brier_r;
  std::vector<uint32_t> weight(k);
  for (int r = 0; r < settings.replicates && k > 0; ++r) {
    std::fill(weight.begin(), weight.end(), 0);
    for (size_t i = 0; i < k; ++i) ++weight[pick(rng)];
    miou_r.push_back(row.miouAll(weight, ignore_class) - reference.miouAll(weight, ignore_class));
    brier_r.push_back(row.brier(weight) - reference.brier(weight));
  }
  d.miou_all = percentileInterval(miou, miou_r, settings.alpha);
  d.brier = percentileInterval(brier, brier_r, settings.alpha);
  return d;
}

}  // namespace evidential_octomap
