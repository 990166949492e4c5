// Integrity of .ot files: a CRC-32 over the semantic section and invariant
// checks after reading, so an altered file never loads as a different map; files of formats 1
// (no CRC) and 2 (inner payloads stored) still load; loadMap reads regular files only;
// readProblem() tells in one call whether OctoMap's generic reader gave a complete map.
#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <iomanip>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "../src/core/crc32.h"
#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "tree_compare.h"

namespace evidential_octomap {
namespace {

using test::compareTrees;

// Files of this process only (ctest -j runs several test binaries at once), in /dev/shm when
// there is one: thousands of files are rewritten here, which a disk makes slow.
class Scratch {
 public:
  Scratch() {
    const std::string base = ::access("/dev/shm", W_OK) == 0 ? "/dev/shm/" : ::testing::TempDir();
    std::string pattern = base + "evidential_integrity_XXXXXX";
    dir_ = ::mkdtemp(&pattern[0]);
  }
  ~Scratch() { std::system(("rm -rf '" + dir_ + "'").c_str()); }
  std::string file(const std::string& name) const { return dir_ + "/" + name; }

 private:
  std::string dir_;
};

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::unique_ptr<EvidentialOcTree> smallMap() {
  auto tree = std::make_unique<EvidentialOcTree>(0.2, 3);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (int i = 0; i < 5; ++i) {
    points.push_back(1.1f, -0.4f + 0.2f * i, 0.1f);
    evidence.insert(evidence.end(), {float(i), 2.0f, 0.5f});
  }
  tree->insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.5f));
  return tree;
}

// The bytes of `tree`'s .ot, with OctoMap's header at full precision.
std::string otBytes(const EvidentialOcTree& tree) {
  std::ostringstream out;
  out << std::setprecision(17);
  tree.write(out);
  return out.str();
}

// `file` must be refused by the reader with an error that contains `message`.
void expectRefused(const Scratch& scratch, const std::string& file, const std::string& message,
                   const std::string& what) {
  const std::string path = scratch.file("refused.ot");
  writeBytes(path, file);
  try {
    loadMap(path);
    ADD_FAILURE() << what << ": loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << what << ": " << e.what();
  }
}

// Where the data section (after OctoMap's "data\n" line) starts.
size_t sectionStart(const std::string& bytes) {
  const size_t at = bytes.find("\ndata\n");
  return at == std::string::npos ? std::string::npos : at + 6;
}

// Recomputes the trailing CRC of a format-2 or -3 file (an edit that a CRC alone would not catch).
void reseal(std::string* bytes) {
  const size_t s = sectionStart(*bytes);
  const uint32_t crc = crc32Update(0, bytes->data() + s, bytes->size() - 4 - s);
  std::memcpy(&(*bytes)[bytes->size() - 4], &crc, 4);
}

// Offset of the root node: after the node count, whose value is the tree's size.
size_t rootOffset(const std::string& bytes, uint64_t size) {
  std::string pattern(8, '\0');
  std::memcpy(&pattern[0], &size, 8);
  return bytes.find(pattern, sectionStart(bytes)) + 8;
}

// The layout of the format documented in ot_format.cpp, used to edit files by hand.
constexpr size_t kVersionOffset = 4;     // after the magic
constexpr size_t kResolutionOffset = 8;  // formats 2 and 3

uint32_t u32At(const std::string& bytes, size_t at) {
  uint32_t v;
  std::memcpy(&v, &bytes[at], 4);
  return v;
}

// Format 3's node records re-encoded as formats 1 and 2 wrote them (an independent encoder of
// the old layout): a has-payload flag on every node, dense payloads, and on inner nodes a copy
// of the richest child's payload (largest sum, first on ties). Returns the payload this node
// stands for (empty: none). `prior` fills the classes a sparse payload leaves out.
std::vector<float> reencodeNode(const std::string& in, size_t* at, int num_classes, float prior,
                                std::string* out) {
  const std::string value_and_mask = in.substr(*at, 5);
  const uint8_t children = static_cast<uint8_t>(in[*at + 4]);
  *at += 5;
  std::vector<float> payload;
  std::string records;
  if (children == 0) {
    const uint8_t tag = static_cast<uint8_t>(in[(*at)++]);
    if (tag == 1) {
      payload.resize(num_classes);
      std::memcpy(payload.data(), &in[*at], 4 * num_classes);
      *at += 4 * num_classes;
    } else if (tag >= 2) {
      payload.assign(num_classes, prior);
      for (int pair = 0; pair < tag - 2; ++pair, *at += 5) {
        std::memcpy(&payload[static_cast<uint8_t>(in[*at])], &in[*at + 1], 4);
      }
    }
  } else {
    double richest = -1e300;
    for (unsigned i = 0; i < 8; ++i) {
      if (!(children & (1u << i))) continue;
      const std::vector<float> child = reencodeNode(in, at, num_classes, prior, &records);
      double sum = 0.0;
      for (float v : child) sum += v;
      if (!child.empty() && sum > richest) {
        richest = sum;
        payload = child;
      }
    }
  }
  *out += value_and_mask;
  *out += static_cast<char>(payload.empty() ? 0 : 1);
  if (!payload.empty()) out->append(reinterpret_cast<const char*>(payload.data()), 4 * num_classes);
  *out += records;
  return payload;
}

// One format-5 node record and its subtree as format 4 wrote them (an independent decoder of
// the log-odds coding): the log-odds as f32 instead of a `width`-byte index into `table`.
void decodeLogOdds(const std::string& in, size_t* at, int width, const std::vector<float>& table,
                   int num_classes, std::string* out) {
  uint32_t index = 0;
  std::memcpy(&index, &in[*at], width);  // little-endian
  *at += width;
  const float value = table.at(index);
  out->append(reinterpret_cast<const char*>(&value), 4);
  const uint8_t children = static_cast<uint8_t>(in[*at]);
  size_t record = 1;  // child mask
  if (children == 0) {
    const uint8_t tag = static_cast<uint8_t>(in[*at + 1]);
    record += 1 + (tag == 1 ? 4 * num_classes : tag >= 2 ? 5 * (tag - 2) : 0);
  }
  out->append(in, *at, record);
  *at += record;
  for (unsigned i = 0; i < 8; ++i) {
    if (children & (1u << i)) decodeLogOdds(in, at, width, table, num_classes, out);
  }
}

// The same map as format 8 wrote it (no ground_vertical_support and ground class flags: the f64
// and C bytes before the node count), from a file of a map without ground classes.
std::string toFormat8(const std::string& bytes, const EvidentialOcTree& tree) {
  EXPECT_TRUE(tree.groundClasses().empty()) << "format 8 cannot say otherwise";
  const size_t s = sectionStart(bytes);
  const size_t classes = static_cast<size_t>(tree.numClasses());
  const size_t field = rootOffset(bytes, tree.size()) - 8 - 8 - classes;
  EXPECT_EQ(bytes.substr(field + 8, classes), std::string(classes, '\0'));
  std::string old = bytes.substr(0, field) + bytes.substr(field + 8 + classes);
  const uint32_t eight = 8;
  std::memcpy(&old[s + kVersionOffset], &eight, 4);
  reseal(&old);
  return old;
}

// The same map as format 7 wrote it (no vertical_support: the f64 before the node count), from a
// format-8 file of a map with a ball support.
std::string toFormat7(const std::string& bytes, const EvidentialOcTree& tree) {
  EXPECT_EQ(tree.config().vertical_support, 1.0) << "format 7 cannot say otherwise";
  const size_t s = sectionStart(bytes);
  const size_t field = rootOffset(bytes, tree.size()) - 8 - 8;
  double value = 0.0;
  std::memcpy(&value, &bytes[field], 8);
  EXPECT_EQ(value, 1.0);
  std::string old = bytes.substr(0, field) + bytes.substr(field + 8);
  const uint32_t seven = 7;
  std::memcpy(&old[s + kVersionOffset], &seven, 4);
  reseal(&old);
  return old;
}

// The same map as format 6 wrote it (no semantic_occupied_only: the u8 before the node count),
// from a format-7 file of a map without it.
std::string toFormat6(const std::string& bytes, const EvidentialOcTree& tree) {
  EXPECT_FALSE(tree.config().semantic_occupied_only) << "format 6 cannot say so";
  const size_t s = sectionStart(bytes);
  const size_t flag = rootOffset(bytes, tree.size()) - 8 - 1;
  EXPECT_EQ(bytes[flag], 0);
  std::string old = bytes.substr(0, flag) + bytes.substr(flag + 1);
  const uint32_t six = 6;
  std::memcpy(&old[s + kVersionOffset], &six, 4);
  reseal(&old);
  return old;
}

// The same map as format 4 wrote it, from a format-6 file whose log-odds are coded by a table.
std::string toFormat4(const std::string& bytes, const EvidentialOcTree& tree) {
  const size_t s = sectionStart(bytes);
  const size_t coding = rootOffset(bytes, tree.size());
  const int width = static_cast<uint8_t>(bytes[coding]);
  EXPECT_LT(width, 4) << "a small map codes its log-odds by a table";
  const uint32_t size = u32At(bytes, coding + 1);
  std::vector<float> table(size);
  std::memcpy(table.data(), &bytes[coding + 5], 4 * size);
  size_t at = coding + 5 + 4 * size;
  std::string nodes;
  decodeLogOdds(bytes, &at, width, table, tree.numClasses(), &nodes);
  // Format 5 had no adaptive-cap statistic (the f64 + u64 before the node count).
  std::string old =
      bytes.substr(0, coding - 24) + bytes.substr(coding - 8, 8) + nodes + bytes.substr(at);
  const uint32_t four = 4;
  std::memcpy(&old[s + kVersionOffset], &four, 4);
  reseal(&old);
  return old;
}

// The same map as format 2 wrote it (inner payloads, dense payloads, no evidence cap: the f64
// before the node count), from a format-4 file.
std::string toFormat2(const std::string& bytes, const EvidentialOcTree& tree) {
  const size_t s = sectionStart(bytes);
  const size_t root = rootOffset(bytes, tree.size());
  size_t at = root;
  std::string nodes;
  reencodeNode(bytes, &at, tree.numClasses(), tree.rule().prior(), &nodes);
  std::string header = bytes.substr(0, root);
  header.erase(root - 16, 8);
  std::string old = header + nodes + bytes.substr(at, bytes.size() - at);  // end magic and CRC
  const uint32_t two = 2;
  std::memcpy(&old[s + kVersionOffset], &two, 4);
  reseal(&old);
  return old;
}

// The same map as format 1 wrote it: no resolution, downsampling and kernel_distance fields
// (the map must use their defaults), no CRC; from a format-2 file.
std::string toFormat1(const std::string& bytes) {
  const size_t s = sectionStart(bytes);
  size_t at = s + kResolutionOffset + 8;  // the class count
  const uint32_t num_classes = u32At(bytes, at);
  at += 4;
  for (uint32_t c = 0; c <= num_classes; ++c) at += 4 + u32At(bytes, at);  // names, the rule
  const size_t dropped_begin = at;
  for (int i = 0; i < 2; ++i) at += 4 + u32At(bytes, at);  // downsampling, kernel_distance
  std::string old = bytes.substr(0, s + kResolutionOffset) +
                    bytes.substr(s + kResolutionOffset + 8, dropped_begin - (s + 16)) +
                    bytes.substr(at, bytes.size() - 4 - at);
  const uint32_t one = 1;
  std::memcpy(&old[s + kVersionOffset], &one, 4);
  return old;
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32Update(0, "123456789", 9), 0xCBF43926u);
  // Incremental and one-shot agree, at every split.
  const std::string text = "The quick brown fox jumps over the lazy dog";
  const uint32_t whole = crc32Update(0, text.data(), text.size());
  EXPECT_EQ(whole, 0x414FA339u);
  for (size_t split = 0; split <= text.size(); ++split) {
    EXPECT_EQ(
        crc32Update(crc32Update(0, text.data(), split), text.data() + split, text.size() - split),
        whole);
  }
}

// Every single-byte alteration of a saved map: refused, or (where the byte does not matter,
// e.g. OctoMap's comment lines) the very same map. Before the CRC, ~6 % of altered files loaded
// as a different map.
TEST(Integrity, NoAlteredFileLoadsAsADifferentMap) {
  Scratch scratch;
  const auto tree = smallMap();
  const std::string good = scratch.file("good.ot");
  saveMap(*tree, good);
  const std::string bytes = readBytes(good);
  const std::string altered = scratch.file("altered.ot");
  size_t refused = 0, same = 0, different = 0;
  std::string first_different;
  for (size_t at = 0; at < bytes.size(); ++at) {
    for (uint8_t mask : {0x01, 0x10, 0x80, 0xFF}) {
      std::string bad = bytes;
      bad[at] = static_cast<char>(bad[at] ^ mask);
      writeBytes(altered, bad);
      std::unique_ptr<EvidentialOcTree> loaded;
      try {
        loaded = loadMap(altered);
      } catch (const std::runtime_error&) {
        ++refused;
        continue;
      }
      if (compareTrees(*tree, *loaded)) {
        ++same;
      } else if (++different == 1) {
        first_different = "byte " + std::to_string(at) + " ^ " + std::to_string(mask);
      }
    }
  }
  EXPECT_EQ(different, 0u) << different
                           << " altered files loaded as a different map (first: " << first_different
                           << ")";
  EXPECT_GT(refused, 4 * (bytes.size() - sectionStart(bytes)) - 1);
  RecordProperty("refused", std::to_string(refused));
  RecordProperty("same", std::to_string(same));
}

TEST(Integrity, Format1To8FilesStillLoad) {
  Scratch scratch;
  for (const std::string rule : {"dempster", "ebs"}) {
    SemanticConfig config;
    config.rule = rule;
    auto tree = std::make_unique<EvidentialOcTree>(0.2, 3, config);
    octomap::Pointcloud points;
    std::vector<float> evidence;
    for (int i = 0; i < 9; ++i) {
      points.push_back(1.1f + 0.1f * (i % 2), -0.8f + 0.2f * i, 0.1f);
      evidence.insert(evidence.end(), {float(i), 2.0f, i % 3 ? 0.0f : 0.5f});
    }
    tree->insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.5f));
    const std::string v8 = toFormat8(otBytes(*tree), *tree), v7 = toFormat7(v8, *tree),
                      v6 = toFormat6(v7, *tree), v4 = toFormat4(v6, *tree),
                      v2 = toFormat2(v4, *tree);
    ASSERT_GT(v4.size(), v6.size()) << "format 4 stores f32 log-odds";
    ASSERT_GT(v2.size(), v4.size()) << "format 2 stores inner payloads";
    for (const auto& [file, format] :
         {std::pair(v8, "format 8"), std::pair(v7, "format 7"), std::pair(v6, "format 6"),
          std::pair(v4, "format 4")}) {
      const std::string path = scratch.file("format.ot");
      writeBytes(path, file);
      std::unique_ptr<EvidentialOcTree> loaded;
      ASSERT_NO_THROW(loaded = loadMap(path)) << rule << ", " << format;
      EXPECT_TRUE(compareTrees(*tree, *loaded)) << rule << ", " << format;
      EXPECT_FALSE(loaded->config().semantic_occupied_only) << format;
      EXPECT_EQ(loaded->config().vertical_support, 1.0) << format << ": a ball, as then";
      EXPECT_TRUE(loaded->groundClasses().empty()) << format << ": no ground class then";
    }
    // Formats before 4 predate the evidence cap: their maps are read without one.
    config.evidence_cap = 0.0;
    tree->setConfig(config);
    for (const std::string& file : {v2, toFormat1(v2)}) {
      const std::string path = scratch.file("old_format.ot");
      writeBytes(path, file);
      std::unique_ptr<EvidentialOcTree> loaded;
      ASSERT_NO_THROW(loaded = loadMap(path)) << rule;
      EXPECT_TRUE(compareTrees(*tree, *loaded)) << rule;
      // And through OctoMap's generic reader.
      std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(path));
      EXPECT_EQ(readProblem(any.get()), "");
    }
  }
}

// An inner node that disagrees with its children: refused in a format-3 file whose CRC was
// recomputed after the edit, and (log-odds or stored evidence) in files of formats 1 and 2.
TEST(Integrity, InnerNodeDisagreeingWithItsChildrenIsRefused) {
  Scratch scratch;
  const auto tree = smallMap();
  ASSERT_TRUE(tree->getRoot()->hasSemantics());
  const std::string v7 = toFormat7(toFormat8(otBytes(*tree), *tree), *tree),
                    v4 = toFormat4(toFormat6(v7, *tree), *tree), v2 = toFormat2(v4, *tree);
  const size_t root = rootOffset(v4, tree->size());
  float root_value;
  std::memcpy(&root_value, &v4[root], 4);
  ASSERT_EQ(root_value, tree->getRoot()->getValue()) << "root offset not found";
  auto refused = [&](const std::string& file, const std::string& what) {
    expectRefused(scratch, file, "inner node", what);
  };
  const float other = root_value + 0.5f;
  for (std::string edited : {v4, v2}) {
    std::memcpy(&edited[root], &other, 4);
    reseal(&edited);
    refused(edited, "log-odds");
    if (edited.size() == v2.size()) refused(toFormat1(edited), "log-odds, format 1");
  }
  // The root's first stored payload entry (after value, child mask and payload flag).
  std::string edited = v2;
  float first;
  std::memcpy(&first, &edited[root + 6], 4);
  first += 1.0f;
  std::memcpy(&edited[root + 6], &first, 4);
  reseal(&edited);
  refused(edited, "evidence, format 2");
  refused(toFormat1(edited), "evidence, format 1");
  // Format 5+: the root's log-odds index pointing at another value of the table.
  const size_t coding = rootOffset(v7, tree->size());
  ASSERT_EQ(v7[coding], 1) << "one byte per log-odds";
  const uint32_t size = u32At(v7, coding + 1);
  ASSERT_GE(size, 2u);
  std::string edited5 = v7;
  const size_t root5 = coding + 5 + 4 * size;
  edited5[root5] = static_cast<char>((static_cast<uint8_t>(edited5[root5]) + 1) % size);
  reseal(&edited5);
  refused(edited5, "log-odds index, format 5");
}

// Format 5's log-odds coding, altered and resealed: refused with what is wrong.
TEST(Integrity, BadLogOddsCodingIsRefused) {
  Scratch scratch;
  const auto tree = smallMap();
  const std::string v5 = otBytes(*tree);
  const size_t coding = rootOffset(v5, tree->size());
  const uint32_t size = u32At(v5, coding + 1);
  ASSERT_GE(size, 2u);
  const auto refusedWith = [&](std::string file, const std::string& message) {
    reseal(&file);
    expectRefused(scratch, file, message, "log-odds coding");
  };
  std::string edited = v5;
  edited[coding] = 3;
  refusedWith(edited, "bad log-odds width");
  edited = v5;
  edited[coding + 5 + 4 * size] = static_cast<char>(size);  // the root's index
  refusedWith(edited, "outside the table");
  edited = v5;
  std::memcpy(&edited[coding + 5], &edited[coding + 9], 4);  // first value == second
  refusedWith(edited, "not finite and increasing");
  edited = v5;
  const uint32_t too_long = 257;
  std::memcpy(&edited[coding + 1], &too_long, 4);
  refusedWith(edited, "too long");
}

// A mutated file whose CRC was resealed loaded with clamps 0.5 + 1e-43 .. 0.5 + 2e-38 (log-odds
// 1.6e-43 .. 2.4e-38): ordered and inside [0.001, 0.999], but every observed voxel clamped to
// "occupied", free space gone. Clamping must never turn free into occupied: refused on reading.
TEST(Integrity, ClampsAboveOrBelowOneHalfAreRefused) {
  Scratch scratch;
  const auto tree = smallMap();
  const std::string original = otBytes(*tree);
  auto offsetOf = [&](float value) {  // the clamp's float in the section, once
    std::string pattern(4, '\0');
    std::memcpy(&pattern[0], &value, 4);
    const size_t at = original.find(pattern, sectionStart(original));
    EXPECT_EQ(original.find(pattern, at + 1), std::string::npos) << value << " twice";
    return at;
  };
  const size_t lo = offsetOf(tree->getClampingThresMinLog());
  const size_t hi = offsetOf(tree->getClampingThresMaxLog());
  ASSERT_NE(lo, std::string::npos);
  ASSERT_NE(hi, std::string::npos);
  const std::pair<float, float> clamps[] = {{1.6e-43f, 2.35e-38f}, {0.4f, 3.0f}, {-2.0f, -0.1f}};
  for (const auto& [min_log, max_log] : clamps) {
    std::string edited = original;
    std::memcpy(&edited[lo], &min_log, 4);
    std::memcpy(&edited[hi], &max_log, 4);
    reseal(&edited);
    const std::string path = scratch.file("clamps.ot");
    writeBytes(path, edited);
    EXPECT_THROW(loadMap(path), std::runtime_error) << min_log << " .. " << max_log;
  }
  // The same models are refused where they are set.
  EXPECT_NE(SensorModel({0.7, 0.4, 0.6, 0.97, 0.5}).problem(), "");
  EXPECT_NE(SensorModel({0.7, 0.4, 0.12, 0.45, 0.5}).problem(), "");
  EXPECT_EQ(SensorModel({0.7, 0.4, 0.5, 0.5001, 0.5}).problem(), "");
  EvidentialOcTree above(0.2, 2);
  above.setClampingThresMin(0.6);
  EXPECT_THROW(saveMap(above, scratch.file("above.ot")), std::runtime_error);
}

// OctoMap's header `res` and the section's exact resolution: rounding (6 digits, what a plain
// tree.write(path) prints) is restored exactly; anything else is corruption.
TEST(Integrity, HeaderResolutionIsCheckedAgainstTheSection) {
  Scratch scratch;
  SemanticConfig config;
  config.length_scale = 0.4;
  EvidentialOcTree tree(0.123456789, 2, config);
  octomap::Pointcloud points;
  points.push_back(1.0f, 0.5f, 0.2f);
  tree.insertSemanticScan(points, {3.0f, 1.0f}, octomap::point3d(0.f, 0.f, 0.f));
  const std::string path = scratch.file("res.ot");
  ASSERT_TRUE(tree.write(path));  // OctoMap's writer: `res 0.123457`
  ASSERT_NE(readBytes(path).find("res 0.123457\n"), std::string::npos);
  EXPECT_EQ(loadMap(path)->getResolution(), 0.123456789);
  std::string bytes = readBytes(path);
  bytes.replace(bytes.find("res 0.123457\n"), 13, "res 0.223457\n");
  writeBytes(path, bytes);
  EXPECT_THROW(loadMap(path), std::runtime_error);
}

TEST(ReadProblem, TellsEveryWayTheGenericReaderCanFall) {
  Scratch scratch;
  EXPECT_NE(readProblem(nullptr), "");
  const auto tree = smallMap();
  const std::string good = scratch.file("good.ot");
  saveMap(*tree, good);
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(good));
  EXPECT_EQ(readProblem(read.get()), "");

  // A corrupt data section: OctoMap returns an empty tree of our type.
  std::string bytes = readBytes(good);
  bytes[bytes.size() - 10] ^= 0x55;
  const std::string corrupt = scratch.file("corrupt.ot");
  writeBytes(corrupt, bytes);
  read.reset(octomap::AbstractOcTree::read(corrupt));
  ASSERT_NE(read, nullptr);
  EXPECT_EQ(read->size(), 0u);
  const auto* ours = dynamic_cast<const EvidentialOcTree*>(read.get());
  ASSERT_NE(ours, nullptr);
  EXPECT_NE(readProblem(read.get()), "");
  EXPECT_EQ(readProblem(read.get()), ours->readError());

  // An empty map: the header says "size 0", OctoMap never reads our section.
  EvidentialOcTree empty(0.2, 7);
  const std::string empty_path = scratch.file("empty.ot");
  saveMap(empty, empty_path);
  read.reset(octomap::AbstractOcTree::read(empty_path));
  ASSERT_NE(read, nullptr);
  EXPECT_NE(readProblem(read.get()).find("loadMap"), std::string::npos);
  EXPECT_EQ(loadMap(empty_path)->numClasses(), 7);

  // Another tree type.
  octomap::OcTree plain(0.2);
  plain.updateNode(octomap::point3d(1, 1, 1), true);
  const std::string plain_path = scratch.file("plain.ot");
  plain.write(plain_path);
  read.reset(octomap::AbstractOcTree::read(plain_path));
  EXPECT_NE(readProblem(read.get()).find("OcTree"), std::string::npos);
}

// Inner nodes whose occupancy is stale (OctoMap's lazy_eval updates leave them so) are not
// written, because the reader would refuse them; updateInnerNodes() makes the map savable.
TEST(Integrity, StaleInnerNodesAreNotWritten) {
  Scratch scratch;
  auto tree = smallMap();
  // A hit far above the rest: the root's log-odds must follow, and lazy_eval leaves them.
  tree->updateNode(octomap::point3d(1.1f, 0.1f, 0.1f), 3.0f, /*lazy_eval=*/true);
  const std::string path = scratch.file("stale.ot");
  EXPECT_THROW(saveMap(*tree, path), std::runtime_error);
  detail::TreeEditing::updateInnerNodes(*tree);
  ASSERT_NO_THROW(saveMap(*tree, path));
  EXPECT_TRUE(compareTrees(*tree, *loadMap(path)));
}

// Format 3 stores no inner summary: after OctoMap's deleteNode (which refreshes occupancy but
// not our summaries) the map is written, and reads back with the summaries derived again.
TEST(Integrity, SummariesAreDerivedAgainOnReading) {
  Scratch scratch;
  auto tree = smallMap();
  octomap::OcTreeKey richest_key;
  double best = -1.0;
  for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it) {
    if (!it->hasSemantics() || it.getDepth() != tree->getTreeDepth()) continue;
    const std::vector<float> p = tree->payload(&*it);
    const double sum = double(p[0]) + p[1] + p[2];
    if (sum > best) {
      best = sum;
      richest_key = it.getKey();
    }
  }
  ASSERT_GT(best, 0.0);
  const EvidentialOcTreeNode* parent = tree->search(richest_key, tree->getTreeDepth() - 1);
  unsigned siblings = 0;
  for (unsigned i = 0; i < 8; ++i) siblings += tree->nodeChildExists(parent, i) ? 1 : 0;
  ASSERT_GE(siblings, 2u) << "OctoMap 1.9 cannot delete an only child";
  tree->deleteNode(richest_key);
  const std::string path = scratch.file("deleted.ot");
  ASSERT_NO_THROW(saveMap(*tree, path));
  const auto loaded = loadMap(path);
  detail::TreeEditing::updateInnerNodes(*tree);
  detail::TreeEditing::compactPayloads(*tree);  // deleteNode leaves the deleted leaf's payload slot in the pool
  EXPECT_TRUE(compareTrees(*tree, *loaded));
}

// --- loadMap on what is not a regular file ------------------------------------------------

// Runs loadMap(path) in a child with a 20 s alarm: a hang guard (opening a FIFO blocks until a
// writer appears), not a timing assertion. Returns the child's exit status: 0 loaded, 1 threw
// std::runtime_error, anything else a hang or crash. (Only for paths refused before a tree is
// made: after fork, OpenMP in a child of a process that used it can deadlock.)
int loadInChild(const std::string& path) {
  const pid_t child = ::fork();
  if (child == 0) {
    ::alarm(20);
    try {
      loadMap(path);
      ::_exit(0);
    } catch (const std::runtime_error& e) {
      ::_exit(std::string(e.what()).find(path) != std::string::npos ? 1 : 3);
    } catch (...) {
      ::_exit(4);
    }
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(LoadMap, RefusesWhatIsNotARegularFileWithoutReadingIt) {
  Scratch scratch;
  const std::string fifo = scratch.file("fifo.ot");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(loadInChild(fifo), 1) << "a FIFO (status 142: blocked until the alarm)";
  EXPECT_EQ(loadInChild("/dev/zero"), 1) << "a device";
  EXPECT_EQ(loadInChild(scratch.file("")), 1) << "a directory";
}

TEST(LoadMap, RefusesAFileLargerThanTheLimit) {
  Scratch scratch;
  const std::string path = scratch.file("map.ot");
  saveMap(*smallMap(), path);
  const uint64_t size = readBytes(path).size();
  EXPECT_NO_THROW(loadMap(path, size));
  EXPECT_THROW(loadMap(path, size - 1), std::runtime_error);
}

}  // namespace
}  // namespace evidential_octomap
