// Deterministic short fuzz run, no clang needed (ctest runs it; see test/reliability).
//
//   fuzz_replay --target ot|class_table|services [--corpus DIR]... [--regressions DIR]
//               [--mutations N] [--seed S] [--save-current FILE] [--verbose]
//
// Runs the target on every corpus file and every regression input as they are, then on N inputs
// mutated from the corpus by a fixed-seed stream (the same inputs on every machine): truncations,
// bit flips, interesting bytes, 32/64-bit length and count fields set to boundary values,
// floats set to NaN/inf/huge/negative, header tokens (id, size, res) rewritten, chunks deleted,
// duplicated or spliced from another seed. A broken invariant aborts (see fuzz_targets.h); with
// --save-current the input being run is written to FILE first, so a crash leaves it behind.
#include <dirent.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "fuzz_targets.h"
#include "mutator.h"

namespace {

using evidential_octomap::fuzz::Bytes;
using evidential_octomap::fuzz::listDir;
using evidential_octomap::fuzz::mutate;
using evidential_octomap::fuzz::readFile;
using evidential_octomap::fuzz::Rng;

}  // namespace

int main(int argc, char** argv) {
  std::string target = "ot", save_current;
  std::vector<std::string> corpus_dirs, regression_dirs;
  long mutations = 2000;
  uint64_t seed = 20261123;
  bool verbose = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << arg << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--target") target = value();
    else if (arg == "--corpus") corpus_dirs.push_back(value());
    else if (arg == "--regressions") regression_dirs.push_back(value());
    else if (arg == "--mutations") mutations = std::stol(value());
    else if (arg == "--seed") seed = std::stoull(value());
    else if (arg == "--save-current") save_current = value();
    else if (arg == "--verbose") verbose = true;
    else {
      std::cerr << "unknown argument " << arg << "\n";
      return 2;
    }
  }
  // scripts/sanitize.sh shortens the run under sanitizers (EVIDENTIAL_FUZZ_MUTATIONS caps it).
  if (const char* cap = std::getenv("EVIDENTIAL_FUZZ_MUTATIONS")) {
    if (std::atol(cap) >= 0) mutations = std::min(mutations, std::atol(cap));
  }
  const bool ot = target == "ot";
  int (*run)(const uint8_t*, size_t) = nullptr;
  if (ot) run = evidential_octomap::fuzz::fuzzOtReader;
  if (target == "class_table") run = evidential_octomap::fuzz::fuzzClassTable;
  if (target == "services") run = evidential_octomap::fuzz::fuzzMapServices;
  if (!run) {
    std::cerr << "--target must be ot, class_table or services\n";
    return 2;
  }
  if (!verbose) {
    evidential_octomap::fuzz::silenceDiagnostics();
    evidential_octomap::fuzz::silenceStderr();
  }

  std::vector<Bytes> corpus;
  for (const auto& dir : corpus_dirs) {
    for (const auto& file : listDir(dir)) corpus.push_back(readFile(file));
  }
  std::vector<std::string> regressions;
  for (const auto& dir : regression_dirs) {
    for (const auto& file : listDir(dir)) regressions.push_back(file);
  }
  if (corpus.empty() && regressions.empty()) {
    std::cerr << "no inputs: give --corpus and/or --regressions directories that hold files\n";
    return 2;
  }

  using Clock = std::chrono::steady_clock;
  double slowest_ms = 0.0;
  long slowest = -1, executed = 0;
  auto execute = [&](const Bytes& input, long id) {
    if (!save_current.empty()) {
      std::ofstream(save_current, std::ios::binary | std::ios::trunc)
          .write(reinterpret_cast<const char*>(input.data()), static_cast<long>(input.size()));
    }
    const auto start = Clock::now();
    run(input.data(), input.size());
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (ms > slowest_ms) {
      slowest_ms = ms;
      slowest = id;
    }
    ++executed;
  };

  evidential_octomap::fuzz::setAlwaysHeavy(true);
  for (const auto& file : regressions) {
    std::cout << "regression " << file << std::endl;
    execute(readFile(file), -1);
  }
  for (size_t i = 0; i < corpus.size(); ++i) execute(corpus[i], -1);
  // Mutated inputs insert a scan one time in four, as under libFuzzer (the insert dominates).
  evidential_octomap::fuzz::setAlwaysHeavy(false);
  Rng rng{seed};
  for (long i = 0; i < mutations && !corpus.empty(); ++i) {
    Bytes input = corpus[static_cast<size_t>(i) % corpus.size()];
    mutate(input, corpus, rng, ot);
    // Three in four with a valid checksum, so most reach the parser and the invariant checks.
    if (ot && rng.below(4) != 0) {
      evidential_octomap::fuzz::resealOtChecksum(input.data(), input.size());
    }
    if (verbose) std::cout << "mutation " << i << " (" << input.size() << " B)\n";
    execute(input, i);
  }
  std::cout << "fuzz_replay " << target << ": " << executed << " inputs (" << regressions.size()
            << " regressions, " << corpus.size() << " seeds, " << mutations
            << " mutations, seed " << seed << "), 0 failures; slowest " << slowest_ms
            << " ms (mutation " << slowest << ")\n";
  return 0;
}
