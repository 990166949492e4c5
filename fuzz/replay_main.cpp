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

namespace {

using Bytes = std::vector<uint8_t>;

// splitmix64: tiny, fast, and the same sequence with every compiler and standard library.
struct Rng {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  size_t below(size_t n) { return n == 0 ? 0 : static_cast<size_t>(next() % n); }
};

Bytes readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::vector<std::string> listDir(const std::string& dir) {
  std::vector<std::string> files;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (const dirent* e = ::readdir(d)) {
      const std::string name = e->d_name;
      if (name == "." || name == ".." || name == "README.md" || name[0] == '.') continue;
      files.push_back(dir + "/" + name);
    }
    ::closedir(d);
  }
  std::sort(files.begin(), files.end());  // readdir order is not deterministic
  return files;
}

// Offset of the binary data section of an .ot file (after the "data\n" line), or 0.
size_t dataOffset(const Bytes& b) {
  static const char kData[] = "\ndata\n";
  auto it = std::search(b.begin(), b.end(), kData, kData + 6);
  return it == b.end() ? 0 : static_cast<size_t>(it - b.begin()) + 6;
}

template <typename T>
void put(Bytes& b, size_t at, T value) {
  if (at + sizeof(T) <= b.size()) std::memcpy(&b[at], &value, sizeof(T));
}

// Rewrites the value of a header token ("id", "size", "res") of an .ot file.
void rewriteToken(Bytes& b, const std::string& token, const std::string& value) {
  const std::string key = "\n" + token + " ";
  auto it = std::search(b.begin(), b.end(), key.begin(), key.end());
  if (it == b.end()) return;
  auto value_begin = it + static_cast<long>(key.size());
  auto value_end = std::find(value_begin, b.end(), '\n');
  const size_t at = static_cast<size_t>(value_begin - b.begin());
  b.erase(value_begin, value_end);
  b.insert(b.begin() + static_cast<long>(at), value.begin(), value.end());
}

void mutate(Bytes& b, const std::vector<Bytes>& corpus, Rng& rng, bool ot) {
  static const uint32_t kInts[] = {0u, 1u, 2u, 7u, 255u, 256u, 4096u, 4097u, 0x7FFFFFFFu,
                                   0x80000000u, 0xFFFFFFFEu, 0xFFFFFFFFu};
  static const float kFloats[] = {0.f, -0.f, -1.f, 1e30f, -1e30f, 3.4e38f, 1e-45f,
                                  __builtin_inff(), -__builtin_inff(), __builtin_nanf("")};
  static const char* kRes[] = {"0", "-0.2", "nan", "inf", "1e-300", "1e300", "0.123456789",
                               "1e-5", "100000", "abc"};
  static const char* kSize[] = {"0", "1", "4294967295", "-1", "999999999999"};
  static const char* kId[] = {"OcTree", "ColorOcTree", "CountingOcTree", "OcTreeStamped",
                              "EvidentialOcTree", "Nope", ""};
  const size_t data = ot ? dataOffset(b) : 0;
  // Offsets in the data section: aligned to the semantic header's 4-byte fields, or anywhere.
  auto where = [&]() -> size_t {
    if (b.empty()) return 0;
    if (data > 0 && data < b.size() && rng.below(2) == 0) {
      const size_t span = std::min<size_t>(b.size() - data, 96);
      return data + rng.below(span);
    }
    return rng.below(b.size());
  };
  const int rounds = 1 + static_cast<int>(rng.below(3));
  for (int r = 0; r < rounds; ++r) {
    switch (rng.below(ot ? 12 : 8)) {
      case 0:  // truncate
        b.resize(rng.below(b.size() + 1));
        break;
      case 1:  // flip 1-8 bits
        for (int i = 1 + static_cast<int>(rng.below(8)); i > 0 && !b.empty(); --i) {
          b[rng.below(b.size())] ^= static_cast<uint8_t>(1u << rng.below(8));
        }
        break;
      case 2:  // interesting byte
        if (!b.empty()) {
          static const uint8_t kBytes[] = {0x00, 0x01, 0x7F, 0x80, 0xFF, '\n', ' ', '-', '[', '{'};
          b[where()] = kBytes[rng.below(sizeof(kBytes))];
        }
        break;
      case 3:  // 32-bit length / count field
        put(b, where(), kInts[rng.below(sizeof(kInts) / sizeof(kInts[0]))]);
        break;
      case 4:  // 64-bit count field
        put(b, where(), static_cast<uint64_t>(kInts[rng.below(12)]) << (rng.below(2) * 32));
        break;
      case 5:  // delete a chunk
        if (!b.empty()) {
          const size_t at = rng.below(b.size());
          const size_t n = std::min(b.size() - at, 1 + rng.below(64));
          b.erase(b.begin() + static_cast<long>(at), b.begin() + static_cast<long>(at + n));
        }
        break;
      case 6:  // duplicate a chunk
        if (!b.empty()) {
          const size_t at = rng.below(b.size());
          const size_t n = std::min(b.size() - at, 1 + rng.below(64));
          const Bytes chunk(b.begin() + static_cast<long>(at),
                            b.begin() + static_cast<long>(at + n));
          b.insert(b.begin() + static_cast<long>(rng.below(b.size() + 1)), chunk.begin(),
                   chunk.end());
        }
        break;
      case 7: {  // splice: this file's head, another seed's tail
        const Bytes& other = corpus[rng.below(corpus.size())];
        const size_t cut = rng.below(b.size() + 1);
        const size_t from = rng.below(other.size() + 1);
        b.resize(cut);
        b.insert(b.end(), other.begin() + static_cast<long>(from), other.end());
        break;
      }
      case 8:  // float field (log-odds, payload, parameters)
      case 9:
        put(b, where(), kFloats[rng.below(sizeof(kFloats) / sizeof(kFloats[0]))]);
        break;
      case 10:  // double parameter (length scale, gamma, ...) in the semantic header
        put(b, where(), static_cast<double>(kFloats[rng.below(sizeof(kFloats) / sizeof(kFloats[0]))]));
        break;
      case 11:  // header tokens
        switch (rng.below(3)) {
          case 0: rewriteToken(b, "res", kRes[rng.below(sizeof(kRes) / sizeof(kRes[0]))]); break;
          case 1: rewriteToken(b, "size", kSize[rng.below(sizeof(kSize) / sizeof(kSize[0]))]); break;
          default: rewriteToken(b, "id", kId[rng.below(sizeof(kId) / sizeof(kId[0]))]); break;
        }
        break;
    }
  }
}

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
