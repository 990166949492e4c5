// The replay harness's input mutator (fuzz/replay_main.cpp), shared with mutation_stats: a
// fixed-seed stream of mutations that is the same with every compiler and standard library.
#pragma once

#include <dirent.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace evidential_octomap {
namespace fuzz {

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

inline Bytes readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline std::vector<std::string> listDir(const std::string& dir) {
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
inline size_t dataOffset(const Bytes& b) {
  static const char kData[] = "\ndata\n";
  auto it = std::search(b.begin(), b.end(), kData, kData + 6);
  return it == b.end() ? 0 : static_cast<size_t>(it - b.begin()) + 6;
}

template <typename T>
void put(Bytes& b, size_t at, T value) {
  if (at + sizeof(T) <= b.size()) std::memcpy(&b[at], &value, sizeof(T));
}

// Rewrites the value of a header token ("id", "size", "res") of an .ot file.
inline void rewriteToken(Bytes& b, const std::string& token, const std::string& value) {
  const std::string key = "\n" + token + " ";
  auto it = std::search(b.begin(), b.end(), key.begin(), key.end());
  if (it == b.end()) return;
  auto value_begin = it + static_cast<long>(key.size());
  auto value_end = std::find(value_begin, b.end(), '\n');
  const size_t at = static_cast<size_t>(value_begin - b.begin());
  b.erase(value_begin, value_end);
  b.insert(b.begin() + static_cast<long>(at), value.begin(), value.end());
}

inline void mutate(Bytes& b, const std::vector<Bytes>& corpus, Rng& rng, bool ot) {
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

}  // namespace fuzz
}  // namespace evidential_octomap
