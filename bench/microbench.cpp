// Google Benchmark micro-benchmarks of the building blocks of the per-scan hot path, on the keys
// of real scans (SemanticKITTI 08 scan 0 at 0.2 m): what each step costs, and bench-only
// alternatives that the core could adopt.
//
//   evidential_microbench [--benchmark_filter=...]   (run from the repository root)
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <unordered_map>
#include <vector>

#include <octomap/OcTree.h>

#include <evidential_octomap/sparse_kernel.h>

#include "bench_data.h"

namespace {

uint64_t spread3(uint64_t x) {
  x &= 0xFFFF;
  x = (x | (x << 32)) & 0x1F00000000FFFFull;
  x = (x | (x << 16)) & 0x1F0000FF0000FFull;
  x = (x | (x << 8)) & 0x100F00F00F00F00Full;
  x = (x | (x << 4)) & 0x10C30C30C30C30C3ull;
  x = (x | (x << 2)) & 0x1249249249249249ull;
  return x;
}
uint64_t morton(const octomap::OcTreeKey& k) {
  return spread3(k[0]) | (spread3(k[1]) << 1) | (spread3(k[2]) << 2);
}

// The keys one scan updates (free + occupied, OctoMap's discretized ray casting), in hash order.
struct ScanKeys {
  std::vector<octomap::OcTreeKey> keys;
  std::vector<octomap::point3d> points;
  octomap::point3d origin;
};

const ScanKeys& scanKeys() {
  static const ScanKeys data = [] {
    int classes = 0;
    const auto scans = evbench::loadKittiScans("data/semantickitti_08_first10",
                                               "config/classes_semantickitti.yaml", 1, &classes);
    octomap::OcTree tree(0.2);
    octomap::KeySet free_cells, occupied_cells;
    tree.computeDiscreteUpdate(scans[0].points_W, scans[0].origin_W, free_cells, occupied_cells, -1);
    ScanKeys out;
    out.keys.assign(free_cells.begin(), free_cells.end());
    out.keys.insert(out.keys.end(), occupied_cells.begin(), occupied_cells.end());
    for (size_t i = 0; i < scans[0].points_W.size(); ++i) out.points.push_back(scans[0].points_W[i]);
    out.origin = scans[0].origin_W;
    return out;
  }();
  return data;
}

std::vector<std::pair<uint64_t, uint32_t>> mortonPairs() {
  const auto& keys = scanKeys().keys;
  std::vector<std::pair<uint64_t, uint32_t>> order(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) order[i] = {morton(keys[i]), uint32_t(i)};
  return order;
}

// What EvidentialOcTree::applyUpdates does today: std::sort of (Morton code, index) pairs.
void BM_SortPairs_StdSort(benchmark::State& state) {
  const auto input = mortonPairs();
  for (auto _ : state) {
    auto order = input;
    std::sort(order.begin(), order.end());
    benchmark::DoNotOptimize(order.data());
  }
  state.SetItemsProcessed(state.iterations() * input.size());
}
BENCHMARK(BM_SortPairs_StdSort)->Unit(benchmark::kMillisecond);

// LSD radix sort on the 48-bit Morton code, 16 bits per pass (3 passes), stable; same result as
// std::sort for distinct codes (and the tie order of duplicates stays the input order).
void radixSortPairs(std::vector<std::pair<uint64_t, uint32_t>>& a,
                    std::vector<std::pair<uint64_t, uint32_t>>& scratch) {
  scratch.resize(a.size());
  std::vector<uint32_t> count(1 << 16);
  for (int pass = 0; pass < 3; ++pass) {
    const int shift = 16 * pass;
    std::fill(count.begin(), count.end(), 0u);
    for (const auto& p : a) ++count[(p.first >> shift) & 0xFFFF];
    uint32_t sum = 0;
    for (auto& c : count) {
      const uint32_t n = c;
      c = sum;
      sum += n;
    }
    for (const auto& p : a) scratch[count[(p.first >> shift) & 0xFFFF]++] = p;
    a.swap(scratch);
  }
}

void BM_SortPairs_Radix16(benchmark::State& state) {
  const auto input = mortonPairs();
  std::vector<std::pair<uint64_t, uint32_t>> scratch;
  {
    auto check = input, ref = input;
    radixSortPairs(check, scratch);
    std::sort(ref.begin(), ref.end());
    if (check != ref) state.SkipWithError("radix sort differs from std::sort");
  }
  for (auto _ : state) {
    auto order = input;
    radixSortPairs(order, scratch);
    benchmark::DoNotOptimize(order.data());
  }
  state.SetItemsProcessed(state.iterations() * input.size());
}
BENCHMARK(BM_SortPairs_Radix16)->Unit(benchmark::kMillisecond);

// Two threads: each sorts half with std::sort, then std::inplace_merge.
void BM_SortPairs_Parallel2(benchmark::State& state) {
  const auto input = mortonPairs();
  for (auto _ : state) {
    auto order = input;
    const auto mid = order.begin() + order.size() / 2;
#pragma omp parallel sections num_threads(2)
    {
#pragma omp section
      std::sort(order.begin(), mid);
#pragma omp section
      std::sort(mid, order.end());
    }
    std::inplace_merge(order.begin(), mid, order.end());
    benchmark::DoNotOptimize(order.data());
  }
  state.SetItemsProcessed(state.iterations() * input.size());
}
BENCHMARK(BM_SortPairs_Parallel2)->Unit(benchmark::kMillisecond)->UseRealTime();

// Ray casting: OctoMap's computeRayKeys for every (discretized) end point of the scan.
void BM_ComputeRayKeys(benchmark::State& state) {
  const auto& data = scanKeys();
  octomap::OcTree tree(0.2);
  octomap::KeyRay ray;
  size_t cells = 0;
  for (auto _ : state) {
    cells = 0;
    for (const auto& p : data.points) {
      if (tree.computeRayKeys(data.origin, p, ray)) cells += ray.size();
    }
    benchmark::DoNotOptimize(cells);
  }
  state.counters["cells_per_scan"] = double(cells);
  state.SetItemsProcessed(state.iterations() * data.points.size());
}
BENCHMARK(BM_ComputeRayKeys)->Unit(benchmark::kMillisecond);

// De-duplicating one scan's keys: std::unordered_set (OctoMap's KeySet) vs sort + unique.
void BM_Dedup_UnorderedSet(benchmark::State& state) {
  const auto& keys = scanKeys().keys;
  for (auto _ : state) {
    octomap::KeySet set;
    for (const auto& k : keys) set.insert(k);
    benchmark::DoNotOptimize(set.size());
  }
  state.SetItemsProcessed(state.iterations() * keys.size());
}
BENCHMARK(BM_Dedup_UnorderedSet)->Unit(benchmark::kMillisecond);

// The kernel: sparseKernel evaluations (the trig functions) per call.
void BM_SparseKernel(benchmark::State& state) {
  std::vector<double> d(4096);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 0.3);
  for (auto& v : d) v = u(rng);
  for (auto _ : state) {
    double s = 0.0;
    for (double v : d) s += evidential_octomap::sparseKernel(v, 0.3, 1.0);
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(state.iterations() * d.size());
}
BENCHMARK(BM_SparseKernel);

// Per-voxel aggregation map of the kernel loop: unordered_map<OcTreeKey, row> emplace, the
// pattern of the kernel loop (each point touches the sphere of keys around it).
void BM_KernelAggregate_UnorderedMap(benchmark::State& state) {
  const auto& keys = scanKeys().keys;
  const size_t n = std::min<size_t>(keys.size(), 300000);
  for (auto _ : state) {
    std::unordered_map<octomap::OcTreeKey, uint32_t, octomap::OcTreeKey::KeyHash> rows;
    rows.reserve(n);
    for (size_t i = 0; i < n; ++i) rows.emplace(keys[i], uint32_t(rows.size()));
    benchmark::DoNotOptimize(rows.size());
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_KernelAggregate_UnorderedMap)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
