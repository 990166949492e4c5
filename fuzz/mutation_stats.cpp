// What happens to mutated map files (docs/experiments/reliability.md): every seed .ot in a
// directory is mutated N times by the replay harness's mutator (mutator.h) and loaded with
// loadMap. Each outcome is counted: refused, loaded as the very same map, loaded as another seed
// (a splice that put one whole valid file after the mutated bytes: no check can refuse it),
// loaded as a different but consistent map, or loaded with broken internal state (an inner node
// that disagrees with its children, an inverted or non-finite sensor model, a readout that is not
// an opinion).
//
//   mutation_stats SEED_DIR [--mutations N] [--seed S] [--reseal]
//
// --reseal recomputes the data section's CRC-32 after each mutation (format 2), i.e. the attack
// of someone who edits a file and fixes its checksum: the invariant checks must still hold.
// Builds against any version of the library that has loadMap (it uses the public API only), so
// the same stream of mutations can be counted before and after a change.
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "fuzz_targets.h"
#include "mutator.h"

namespace {

using evidential_octomap::EvidentialOcTree;
using evidential_octomap::EvidentialOcTreeNode;
using evidential_octomap::fuzz::Bytes;

std::string written(const EvidentialOcTree& tree) {
  std::ostringstream out;
  out << std::setprecision(17);
  tree.write(out);
  return out.str();
}

// "" when the tree's internal state is consistent, else what is broken.
std::string brokenState(const EvidentialOcTree& tree) {
  const double hit = tree.getProbHit(), miss = tree.getProbMiss();
  const double lo = tree.getClampingThresMin(), hi = tree.getClampingThresMax();
  for (double p : {hit, miss, lo, hi}) {
    if (!(p > 0.0 && p < 1.0)) return "sensor model probability outside (0, 1)";
  }
  if (!(hit >= 0.5 && miss <= 0.5 && lo < hi)) return "inverted sensor model";
  if (!(lo <= 0.5 && hi >= 0.5)) return "clamping turns free into occupied or the reverse";
  for (auto it = tree.begin_tree(), end = tree.end_tree(); it != end; ++it) {
    const EvidentialOcTreeNode* node = &*it;
    const auto o = tree.opinion(node);
    if (!std::isfinite(o.uncertainty)) return "readout uncertainty not finite";
    for (float b : o.belief) {
      if (!std::isfinite(b)) return "readout belief not finite";
    }
    if (!tree.nodeHasChildren(node)) continue;
    float max_child = -std::numeric_limits<float>::max();
    std::vector<float> richest;
    double richest_sum = -1.0;
    for (unsigned i = 0; i < 8; ++i) {
      if (!tree.nodeChildExists(node, i)) continue;
      const EvidentialOcTreeNode* child = tree.getNodeChild(node, i);
      max_child = std::max(max_child, child->getLogOdds());
      if (const std::vector<float> p = tree.payload(child); !p.empty()) {
        const double sum = std::accumulate(p.begin(), p.end(), 0.0);
        if (richest.empty() || sum > richest_sum) {
          richest = p;
          richest_sum = sum;
        }
      }
    }
    if (node->getLogOdds() != max_child) return "inner log-odds != max of children";
    const std::vector<float> own = tree.payload(node);
    if (own.empty() != richest.empty()) return "inner evidence without children's";
    if (own != richest) return "inner evidence != richest child's";
  }
  return "";
}

// The bytes as a file loadMap can open, without touching the disk.
std::string memFile(const Bytes& bytes, int* fd) {
  *fd = ::memfd_create("mutation_stats", 0);
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(*fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) break;
    done += size_t(n);
  }
  return "/proc/self/fd/" + std::to_string(*fd);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: mutation_stats SEED_DIR [--mutations N] [--seed S] [--reseal]\n";
    return 2;
  }
  long mutations = 6000;
  uint64_t seed = 20261124;
  bool reseal = false;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--mutations" && i + 1 < argc)
      mutations = std::stol(argv[++i]);
    else if (arg == "--seed" && i + 1 < argc)
      seed = std::stoull(argv[++i]);
    else if (arg == "--reseal")
      reseal = true;
  }
  // Seeds: our own maps only (the mutations of foreign files say nothing about ours).
  std::vector<Bytes> seeds;
  std::vector<std::string> reference;
  for (const std::string& file : evidential_octomap::fuzz::listDir(argv[1])) {
    try {
      const auto tree = evidential_octomap::loadMap(file);
      seeds.push_back(evidential_octomap::fuzz::readFile(file));
      reference.push_back(written(*tree));
    } catch (const std::exception&) {
    }
  }
  if (seeds.empty()) {
    std::cerr << "no loadable EvidentialOcTree seeds in " << argv[1] << "\n";
    return 2;
  }
  evidential_octomap::fuzz::silenceDiagnostics();  // thousands of expected "corrupt" lines
  evidential_octomap::fuzz::silenceStderr();
  evidential_octomap::fuzz::Rng rng{seed};
  long refused = 0, same = 0, other_seed = 0, different = 0, broken = 0;
  std::string first_broken;
  for (long i = 0; i < mutations; ++i) {
    const size_t s = size_t(i) % seeds.size();
    Bytes input = seeds[s];
    evidential_octomap::fuzz::mutate(input, seeds, rng, true);
#ifndef EVIDENTIAL_NO_RESEAL  // (defined when built against a library before format 2)
    if (reseal) evidential_octomap::fuzz::resealOtChecksum(input.data(), input.size());
#endif
    int fd = -1;
    const std::string path = memFile(input, &fd);
    try {
      const auto tree = evidential_octomap::loadMap(path);
      const std::string problem = brokenState(*tree);
      if (!problem.empty()) {
        if (broken++ == 0) first_broken = "mutation " + std::to_string(i) + ": " + problem;
      } else if (const std::string got = written(*tree); got == reference[s]) {
        ++same;
      } else if (std::find(reference.begin(), reference.end(), got) != reference.end()) {
        ++other_seed;
      } else {
        ++different;
      }
    } catch (const std::exception&) {
      ++refused;
    }
    ::close(fd);
  }
  std::cout << "mutation_stats: " << mutations << " mutations of " << seeds.size() << " seeds"
            << (reseal ? " (checksum resealed)" : "") << ": refused " << refused
            << ", loaded as the same map " << same << ", loaded as another seed map " << other_seed
            << ", loaded as a different map " << different << ", loaded with broken internal state "
            << broken << (first_broken.empty() ? "" : " (first: " + first_broken + ")") << "\n";
  return 0;
}
