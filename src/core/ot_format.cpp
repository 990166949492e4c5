// The data section of an EvidentialOcTree .ot file (what AbstractOcTree::write puts after OctoMap's
// text header "id / size / res / data"). Little-endian, format 9:
//
//   u32 magic "EVEM", u32 format, f64 resolution (2+), u32 C, C x string class name,
//   string rule, string downsampling (2+), string kernel_distance (2+), 7 x f64 (length_scale
//   sigma0 beta gamma drop_percent ds_multiplier max_range), 5 x u8 flags, f32 sbki_prior,
//   5 x f32 occupancy log-odds (clamp min, clamp max, hit, miss, threshold), f64 evidence_cap
//   (4+; older maps are read without a cap, as they were written), f64 + u64 the adaptive
//   cap's statistic (sum and count, 6+; evidence_cap -1 = adaptive), u8 semantic_occupied_only
//   (7+; older maps kept evidence in free space too), f64 vertical_support (8+; older maps had a
//   ball), f64 ground_vertical_support and C x u8 ground class flags (9+; older maps had no
//   ground class), u64 node count, log-odds coding (5+),
//   nodes in depth-first order, u32 end magic, u32 CRC-32 (2+) of every byte from the magic to
//   the end magic.
//   log-odds coding (5+): u8 width W (1, 2 or 4); for W < 4 u32 T (<= 256 for W = 1,
//             <= 65536 for W = 2) and T x f32: the map's distinct log-odds, increasing (-0 before
//             +0), and a node's log-odds is then its W-byte index in this table (log_odds_table.h)
//   node (3+): log-odds (f32 up to format 4; 5+: W bytes), u8 child mask, and for a leaf a u8
//             payload tag:
//             0 no payload; 1 C x f32; 2 + n: n x (u8 class, f32 value), the classes whose value
//             differs (in its bits) from the rule's prior, in increasing order. The writer takes
//             the shorter form. Inner nodes store no payload: their summary (the richest
//             child's) is derived again on reading.
//   node (1, 2): f32 log-odds, u8 child mask, u8 has-payload, [C x f32 payload], inner nodes too
//   string: u32 length (<= 4096), bytes
//
// Format 1 (before the CRC) has no resolution field and no CRC; formats 1 to 8 are still read.
// OctoMap's own header prints `res` with the stream's precision (6 digits unless the writer sets
// more), so formats 2+ keep the exact resolution in the section and the reader restores it.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <octomap/octomap_utils.h>

#include "crc32.h"
#include "section_writer.h"
#include "log_odds_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "payload_store.h"
#include "tree_edit.h"

namespace evidential_octomap {
namespace {

constexpr uint32_t kFileMagic = 0x4D455645u;  // "EVEM"
constexpr uint32_t kFileEndMagic = kSectionEndMagic;
constexpr uint32_t kFormatWithoutCrc = 1;
constexpr uint32_t kFormatWithInnerPayloads = 2;
constexpr uint32_t kFormatSparseNodes = 3;  // no inner payloads, sparse leaf payloads
constexpr uint32_t kFormatEvidenceCap = 4;
constexpr uint32_t kFormatLogOddsTable = 5;  // log-odds coded by a table
constexpr uint32_t kFormatAdaptiveCap = 6;    // the adaptive cap's statistic
constexpr uint32_t kFormatSurfaceEvidence = 7;  // semantic_occupied_only
constexpr uint32_t kFormatVerticalSupport = 8;
constexpr uint32_t kFormatGroundClasses = 9;
constexpr uint32_t kFormat = 9;
constexpr uint32_t kMaxNameLength = 4096;
constexpr uint8_t kNoPayloadTag = 0;
constexpr uint8_t kDenseTag = 1;
constexpr uint8_t kSparseTag = 2;  // + number of (class, value) pairs

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

// Every node in the file's order: depth first, child 0 first. Stops, returning false, when
// visit(node) does.
template <class Visit>
bool forEachNode(const EvidentialOcTree& tree, const EvidentialOcTreeNode* root, Visit visit) {
  std::vector<const EvidentialOcTreeNode*> stack{root};
  while (!stack.empty()) {
    const EvidentialOcTreeNode* node = stack.back();
    stack.pop_back();
    if (!visit(node)) return false;
    if (!tree.nodeHasChildren(node)) continue;
    for (int i = 7; i >= 0; --i) {
      const unsigned child = static_cast<unsigned>(i);
      if (tree.nodeChildExists(node, child)) stack.push_back(tree.getNodeChild(node, child));
    }
  }
  return true;
}

// Thrown inside readData only; turned into read_error_ there.
struct FormatError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The shared validation of everything a file stores besides nodes. `occupancy` holds the
// log-odds in file order: clamp min, clamp max, hit, miss, occupancy threshold.
std::string storedParameterProblem(double resolution, const float (&occupancy)[5],
                                   const SemanticConfig& config) {
  if (!(resolution >= EvidentialOcTree::kMinResolution &&
        resolution <= EvidentialOcTree::kMaxResolution)) {
    return "resolution " + std::to_string(resolution) + " outside [1e-6, 1e6]";
  }
  const std::string problem = SensorModel::problemOfLogOdds(
      occupancy[2], occupancy[3], occupancy[0], occupancy[1], occupancy[4]);
  return problem.empty() ? config.problem() : problem;
}

}  // namespace

class EvidentialOcTree::SectionReader {
 public:
  explicit SectionReader(std::istream& s) : s_(s) {}
  void bytes(void* data, size_t size, const char* what) {
    if (!s_.read(static_cast<char*>(data), static_cast<std::streamsize>(size))) {
      throw FormatError(std::string("truncated ") + what);
    }
    crc_ = crc32Update(crc_, data, size);
  }
  template <typename T>
  T pod(const char* what) {
    T value;
    bytes(&value, sizeof(T), what);
    return value;
  }
  std::string string(const char* what) {
    const uint32_t length = pod<uint32_t>(what);
    if (length > kMaxNameLength) throw FormatError(std::string(what) + " longer than 4096 bytes");
    std::string text(length, '\0');
    bytes(&text[0], length, what);
    return text;
  }
  uint32_t crc() const { return crc_; }
  std::istream& stream() { return s_; }

 private:
  std::istream& s_;
  uint32_t crc_ = 0;
};

std::string EvidentialOcTree::parameterProblem() const {
  const float occupancy[5] = {clamping_thres_min, clamping_thres_max, prob_hit_log, prob_miss_log,
                              occ_prob_thres_log};
  return storedParameterProblem(resolution, occupancy, config_);
}

std::string EvidentialOcTree::insertProblem() const {
  if (log_clamps_set_ && clamping_thres_min == log_clamp_min_ &&
      clamping_thres_max == log_clamp_max_) {
    // Bounds of setClampingThresLog (finite, min <= 0 <= max): any such pair may be in use
    // while mapping; the rest is checked with the default bounds in their place.
    const float occupancy[5] = {static_cast<float>(octomap::logodds(0.12)),  // OctoMap's defaults
                                static_cast<float>(octomap::logodds(0.97)),
                                prob_hit_log, prob_miss_log, occ_prob_thres_log};
    return storedParameterProblem(resolution, occupancy, config_);
  }
  return parameterProblem();
}

std::string EvidentialOcTree::innerNodeProblem(const EvidentialOcTreeNode* node) const {
  if (node->getLogOdds() != node->getMaxChildLogOdds()) {
    return "an inner node's log-odds " + std::to_string(node->getLogOdds()) +
           " are not its children's maximum " + std::to_string(node->getMaxChildLogOdds());
  }
  return "";
}

// How a file codes its nodes: its format and (5+) the log-odds table.
struct NodeCoding {
  uint32_t version = 0;
  int width = 4;             // bytes of a node's log-odds: 1 or 2 (index into `table`) or 4 (f32)
  std::vector<float> table;  // increasing (LogOddsTable::before)
};

// --- writing ---------------------------------------------------------------------------------

std::ostream& EvidentialOcTree::writeData(std::ostream& s) const {
  // A map whose parameters the reader would refuse is not written at all.
  const std::string problem = parameterProblem();
  if (!problem.empty()) {
    OCTOMAP_ERROR_STR("EvidentialOcTree: not written: " << problem);
    s.setstate(std::ios::failbit);
    return s;
  }
  SectionWriter out(s);
  writeHeader(out);
  out.pod(static_cast<uint64_t>(tree_size));
  LogOddsTable table;
  if (root) {
    forEachNode(*this, root, [&table](const EvidentialOcTreeNode* node) {
      table.add(node->getValue());
      return true;
    });
  }
  table.finish();
  out.pod(static_cast<uint8_t>(table.width()));
  if (table.width() < 4) {
    out.pod(static_cast<uint32_t>(table.values().size()));
    for (float v : table.values()) out.pod(v);
  }
  if (root && !writeNodes(root, table, out)) {
    out.flush();
    OCTOMAP_ERROR_STR(
        "EvidentialOcTree: not written: inner nodes are stale (call "
        "updateInnerNodes() after lazy_eval updates)");
    s.setstate(std::ios::failbit);
    return s;
  }
  out.pod(kFileEndMagic);
  const uint32_t crc = out.crc();
  s.write(reinterpret_cast<const char*>(&crc), sizeof(crc));
  return s;
}

void EvidentialOcTree::writeHeader(SectionWriter& out) const {
  out.pod(kFileMagic);
  out.pod(kFormat);
  out.pod(resolution);
  out.pod(static_cast<uint32_t>(num_classes_));
  for (const auto& name : class_names_) out.string(name);
  out.string(config_.rule);
  out.string(config_.downsampling);
  out.string(config_.kernel_distance);
  for (double v : {config_.length_scale, config_.sigma0, config_.beta, config_.gamma,
                   config_.drop_percent, config_.ds_multiplier, config_.max_range}) {
    out.pod(v);
  }
  for (bool flag : {config_.adaptive_length, config_.uncertainty_threshold,
                    config_.reference_compat, config_.kernel_creates_leaves, config_.discretize}) {
    out.pod(static_cast<uint8_t>(flag));
  }
  out.pod(config_.sbki_prior);
  for (float v : {clamping_thres_min, clamping_thres_max, prob_hit_log, prob_miss_log,
                  occ_prob_thres_log}) {  // the order storedParameterProblem() reads
    out.pod(v);
  }
  out.pod(config_.evidence_cap);
  out.pod(evidence_log_sum_);
  out.pod(static_cast<uint64_t>(evidence_points_));
  out.pod(static_cast<uint8_t>(config_.semantic_occupied_only));
  out.pod(config_.vertical_support);
  out.pod(config_.ground_vertical_support);
  for (int c = 0; c < num_classes_; ++c) out.pod(static_cast<uint8_t>(isGroundClass(c)));
}

// Depth first, child 0 first. Returns false (and stops) at the first inner node whose occupancy
// disagrees with its children: the reader would refuse the file.
bool EvidentialOcTree::writeNodes(const EvidentialOcTreeNode* root_node, const LogOddsTable& table,
                                  SectionWriter& out) const {
  const float prior = rule_->prior();
  return forEachNode(*this, root_node, [&](const EvidentialOcTreeNode* node) {
    uint8_t children = 0;
    for (unsigned i = 0; i < 8; ++i) {
      if (nodeChildExists(node, i)) children |= static_cast<uint8_t>(1u << i);
    }
    if (children != 0 && !innerNodeProblem(node).empty()) return false;
    switch (table.width()) {
      case 1: out.pod(static_cast<uint8_t>(table.code(node->getValue()))); break;
      case 2: out.pod(static_cast<uint16_t>(table.code(node->getValue()))); break;
      default: out.pod(node->getValue());
    }
    out.pod(children);
    if (children == 0) writePayload(node, prior, out);
    return true;
  });
}

// A leaf's payload tag and payload, in the shorter form (format 3).
void EvidentialOcTree::writePayload(const EvidentialOcTreeNode* leaf, float prior,
                                    SectionWriter& out) const {
  if (!leaf->hasSemantics()) return out.pod(kNoPayloadTag);
  float payload[kMaxClasses];
  this->payload(leaf, payload);
  int differing = 0;
  for (int c = 0; c < num_classes_; ++c) differing += sameBits(payload[c], prior) ? 0 : 1;
  if (5 * differing < 4 * num_classes_ && differing <= 255 - kSparseTag) {  // 5 B vs 4 B a class
    out.pod(static_cast<uint8_t>(kSparseTag + differing));
    for (int c = 0; c < num_classes_; ++c) {
      if (sameBits(payload[c], prior)) continue;
      out.pod(static_cast<uint8_t>(c));
      out.pod(payload[c]);
    }
  } else {
    out.pod(kDenseTag);
    out.bytes(payload, sizeof(float) * num_classes_);
  }
}

// --- reading ---------------------------------------------------------------------------------

std::istream& EvidentialOcTree::readData(std::istream& s) {
  read_error_.clear();
  created_for_read_ = false;
  try {
    if (root) throw FormatError("cannot read into a tree that is not empty");
    SectionReader in(s);
    if (in.pod<uint32_t>("semantic header") != kFileMagic) {
      throw FormatError("no EvidentialOcTree semantic header (corrupt or foreign data)");
    }
    const uint32_t version = in.pod<uint32_t>("semantic header");
    if (version < kFormatWithoutCrc || version > kFormat) {
      throw FormatError("unsupported EvidentialOcTree file format " + std::to_string(version) +
                        " (this library reads formats 1 to 5)");
    }
    readHeader(in, version);
    const uint64_t expected_nodes = in.pod<uint64_t>("node count");
    const NodeCoding coding = readNodeCoding(in, version);
    if (expected_nodes > 0) {
      root = new EvidentialOcTreeNode();
      tree_size = 1;
      Edit edit(pool_.get(), 1024);
      try {
        readNodesRecurs(root, 0, coding, in, edit);
      } catch (...) {
        commit(edit);
        throw;
      }
      commit(edit);
    }
    if (tree_size != expected_nodes || in.pod<uint32_t>("end marker") != kFileEndMagic) {
      throw FormatError("node data does not match its header (corrupt or truncated)");
    }
    if (version >= kFormatWithInnerPayloads) {
      const uint32_t computed = in.crc();
      uint32_t stored = 0;
      if (!s.read(reinterpret_cast<char*>(&stored), sizeof(stored))) {
        throw FormatError("truncated checksum");
      }
      if (stored != computed) throw FormatError("checksum mismatch (corrupt file)");
    }
    size_changed = true;
  } catch (const std::exception& e) {
    read_error_ = std::string("EvidentialOcTree: ") + e.what();
    clear();
    OCTOMAP_ERROR_STR(read_error_);
    s.setstate(std::ios::failbit);
  }
  return s;
}

void EvidentialOcTree::readHeader(SectionReader& in, uint32_t version) {
  if (version >= kFormatWithInnerPayloads) {
    // OctoMap's text header may have rounded `res`; the section has it exactly. Anything more
    // than rounding apart means one of them is corrupt.
    const double exact = in.pod<double>("resolution");
    if (!(std::fabs(exact - resolution) <= 1e-5 * std::fabs(exact))) {
      throw FormatError("resolution " + std::to_string(resolution) +
                        " of the OctoMap header disagrees with the section's " +
                        std::to_string(exact));
    }
    setResolution(exact);
  }
  const uint32_t num_classes = in.pod<uint32_t>("class count");
  if (num_classes < 1 || num_classes > kMaxClasses) {
    throw FormatError("class count out of range: " + std::to_string(num_classes));
  }
  setNumClasses(static_cast<int>(num_classes));
  std::vector<std::string> names(num_classes);
  for (auto& name : names) name = in.string("class names");
  SemanticConfig config;
  config.rule = in.string("rule name");
  if (version >= kFormatWithInnerPayloads) {  // format 1 predates them: their defaults
    config.downsampling = in.string("downsampling");
    config.kernel_distance = in.string("kernel distance");
  }
  for (double* v : {&config.length_scale, &config.sigma0, &config.beta, &config.gamma,
                    &config.drop_percent, &config.ds_multiplier, &config.max_range}) {
    *v = in.pod<double>("parameters");
  }
  for (bool* flag : {&config.adaptive_length, &config.uncertainty_threshold,
                     &config.reference_compat, &config.kernel_creates_leaves, &config.discretize}) {
    const uint8_t byte = in.pod<uint8_t>("parameters");
    if (byte > 1) throw FormatError("bad parameter flag");
    *flag = byte != 0;
  }
  config.sbki_prior = in.pod<float>("parameters");
  float occupancy[5];
  for (float& v : occupancy) v = in.pod<float>("occupancy parameters");
  config.evidence_cap = version >= kFormatEvidenceCap ? in.pod<double>("evidence cap") : 0.0;
  double log_sum = 0.0;
  uint64_t points = 0;
  if (version >= kFormatAdaptiveCap) {
    log_sum = in.pod<double>("evidence statistic");
    points = in.pod<uint64_t>("evidence statistic");
    if (!(std::isfinite(log_sum) && log_sum >= 0.0) || (points == 0) != (log_sum == 0.0)) {
      throw FormatError("bad evidence statistic");
    }
  }
  if (version >= kFormatSurfaceEvidence) {
    const uint8_t byte = in.pod<uint8_t>("parameters");
    if (byte > 1) throw FormatError("bad parameter flag");
    config.semantic_occupied_only = byte != 0;
  }
  if (version >= kFormatVerticalSupport) config.vertical_support = in.pod<double>("parameters");
  std::vector<bool> ground;  // none before format 9
  if (version >= kFormatGroundClasses) {
    config.ground_vertical_support = in.pod<double>("parameters");
    ground.resize(names.size());
    for (size_t c = 0; c < names.size(); ++c) {
      const uint8_t byte = in.pod<uint8_t>("ground class flags");
      if (byte > 1) throw FormatError("bad ground class flag");
      ground[c] = byte != 0;
    }
    if (std::none_of(ground.begin(), ground.end(), [](bool g) { return g; })) ground.clear();
  }
  const std::string problem = storedParameterProblem(resolution, occupancy, config);
  if (!problem.empty()) throw FormatError("bad parameters: " + problem);
  setConfig(config);
  evidence_log_sum_ = log_sum;
  evidence_points_ = static_cast<size_t>(points);
  followEvidenceStatistic();
  setClassNames(names);
  setGroundClasses(ground);
  clamping_thres_min = occupancy[0];
  clamping_thres_max = occupancy[1];
  prob_hit_log = occupancy[2];
  prob_miss_log = occupancy[3];
  occ_prob_thres_log = occupancy[4];
}

NodeCoding EvidentialOcTree::readNodeCoding(SectionReader& in, uint32_t version) {
  NodeCoding coding;
  coding.version = version;
  if (version < kFormatLogOddsTable) return coding;  // f32 log-odds
  coding.width = in.pod<uint8_t>("log-odds coding");
  if (coding.width != 1 && coding.width != 2 && coding.width != 4) {
    throw FormatError("bad log-odds width " + std::to_string(coding.width));
  }
  if (coding.width == 4) return coding;
  const uint32_t size = in.pod<uint32_t>("log-odds table");
  if (size > (coding.width == 1 ? 256u : LogOddsTable::kMaxValues)) {
    throw FormatError("log-odds table too long for its width");
  }
  coding.table.resize(size);
  in.bytes(coding.table.data(), sizeof(float) * size, "log-odds table");
  for (uint32_t i = 0; i < size; ++i) {
    if (!std::isfinite(coding.table[i]) ||
        (i > 0 && !LogOddsTable::before(coding.table[i - 1], coding.table[i]))) {
      throw FormatError("log-odds table not finite and increasing (corrupt)");
    }
  }
  return coding;
}

void EvidentialOcTree::readNodesRecurs(EvidentialOcTreeNode* node, unsigned depth,
                                       const NodeCoding& coding, SectionReader& in, Edit& edit) {
  float value;
  if (coding.width == 4) {
    value = in.pod<float>("node data");
  } else {
    const uint32_t index =
        coding.width == 1 ? in.pod<uint8_t>("node data") : in.pod<uint16_t>("node data");
    if (index >= coding.table.size()) {
      throw FormatError("a node's log-odds index is outside the table (corrupt node data)");
    }
    value = coding.table[index];
  }
  const uint8_t children = in.pod<uint8_t>("node data");
  if (!std::isfinite(value)) throw FormatError("a node's log-odds are not finite");
  if (depth == tree_depth && children != 0) {
    throw FormatError("a node lies deeper than the tree (corrupt node data)");
  }
  node->setValue(value);
  std::vector<float> summary;  // formats 1 and 2: the stored summary of an inner node
  if (coding.version < kFormatSparseNodes) {
    const uint8_t has_payload = in.pod<uint8_t>("node data");
    if (has_payload > 1) throw FormatError("bad payload flag (corrupt node data)");
    if (has_payload && children != 0) {
      summary.resize(num_classes_);
      in.bytes(summary.data(), sizeof(float) * num_classes_, "node data");
    } else if (has_payload) {
      readPayload(node, kDenseTag, in, edit);
    }
  } else if (children == 0) {
    readPayload(node, in.pod<uint8_t>("node data"), in, edit);
  }
  for (unsigned i = 0; i < 8; ++i) {
    if (children & (1u << i)) {
      readNodesRecurs(createChild(node, i, edit), depth + 1, coding, in, edit);
    }
  }
  if (children == 0) return;
  const std::string problem = innerNodeProblem(node);
  if (!problem.empty()) throw FormatError(problem + " (corrupt node data)");
  linkSummary(node);
  if (coding.version < kFormatSparseNodes) {
    // The stored summary must be the one derived from the children.
    const std::vector<float> derived = payload(node);
    if (derived.empty() != summary.empty() ||
        !std::equal(summary.begin(), summary.end(), derived.begin(), sameBits)) {
      throw FormatError(!derived.empty()
                            ? "an inner node's evidence is not its richest child's"
                            : "an inner node holds evidence none of its children holds");
    }
  }
}

// A leaf's payload after its tag (kDenseTag for formats 1 and 2).
void EvidentialOcTree::readPayload(EvidentialOcTreeNode* leaf, uint8_t tag, SectionReader& in,
                                   Edit& edit) {
  if (tag == kNoPayloadTag) return;
  const float prior = rule_->prior();
  float data[kMaxClasses];
  std::fill_n(data, num_classes_, prior);
  if (tag == kDenseTag) {
    in.bytes(data, sizeof(float) * num_classes_, "node data");
  } else {
    int previous = -1;
    for (int pair = 0; pair < tag - kSparseTag; ++pair) {
      const uint8_t c = in.pod<uint8_t>("node data");
      if (c <= previous || c >= num_classes_) {
        throw FormatError("bad class in a sparse payload (corrupt node data)");
      }
      previous = c;
      data[c] = in.pod<float>("node data");
    }
  }
  // Every writer keeps payloads at or above the rule's prior (dempster: L >= 0); anything
  // else reads out as NaN or negative beliefs.
  for (int c = 0; c < num_classes_; ++c) {
    if (!std::isfinite(data[c]) || data[c] < prior) {
      throw FormatError("a payload is not finite or below the rule's prior");
    }
  }
  storeLeafValues(leaf, data, edit);
}

}  // namespace evidential_octomap
