#include "fuzz_targets.h"

#include <fcntl.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <typeinfo>
#include <vector>

#include "../src/core/crc32.h"
#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/map_editing.h"

// Where sanitizers write their reports (weak: absent in builds without sanitizers).
extern "C" void __sanitizer_set_report_fd(void* fd) __attribute__((weak));
extern "C" void __sanitizer_report_error_summary(const char* summary) __attribute__((weak));

namespace evidential_octomap {
namespace fuzz {
namespace {

int g_report_fd = 2;  // where fuzzFail writes; silenceStderr() keeps it on the real stderr
bool g_always_heavy = false;

// An anonymous in-memory file holding the bytes, reachable by path (/proc/self/fd/N), so the
// path-based loaders (loadMap, ClassTable::load) run without touching the disk.
class MemFile {
 public:
  MemFile(const uint8_t* data, size_t size) {
    fd_ = ::memfd_create("evidential_fuzz", 0);
    if (fd_ < 0) fuzzFail(std::string("memfd_create: ") + std::strerror(errno));
    size_t done = 0;
    while (done < size) {
      const ssize_t n = ::write(fd_, data + done, size - done);
      if (n <= 0) fuzzFail(std::string("write memfd: ") + std::strerror(errno));
      done += static_cast<size_t>(n);
    }
    path_ = "/proc/self/fd/" + std::to_string(fd_);
  }
  ~MemFile() { ::close(fd_); }
  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

// The tree type named by an .ot header, parsed by OctoMap's own header reader ("" when the
// header is not readable). AbstractOcTree::readHeader is protected: reached through a subclass.
struct OtHeader {
  std::string id;     // "" when the header is not readable
  unsigned size = 0;  // node count announced by the header
};
struct OtHeaderReader : octomap::AbstractOcTree {
  static OtHeader parse(const std::string& bytes) {
    OtHeader header;
    std::istringstream s(bytes);
    std::string line;
    std::getline(s, line);
    double res = 0.0;
    if (line.compare(0, fileHeader.length(), fileHeader) != 0 ||
        !readHeader(s, header.id, header.size, res)) {
      header.id.clear();
    }
    return header;
  }
};

void require(bool condition, const std::string& what) {
  if (!condition) fuzzFail(what);
}

// Every readout of a successfully read map must be a valid opinion: that is what a planner or
// viewer consumes, and a reader that accepts a file must not hand out NaN.
void checkOpinion(const EvidentialOcTree& tree, const EvidentialOcTreeNode* node,
                  const char* stage) {
  const VoxelOpinion o = tree.opinion(node);
  const auto require = [stage](bool condition, const char* what) {
    if (!condition) fuzzFail(std::string(stage) + ": " + what);
  };
  const int num_classes = tree.numClasses();
  require(static_cast<int>(o.belief.size()) == num_classes, "readout has the wrong class count");
  require(o.label >= -1 && o.label < num_classes, "readout label out of range");
  require(std::isfinite(o.uncertainty), "readout uncertainty is not finite");
  double sum = o.uncertainty;
  for (float b : o.belief) {
    require(std::isfinite(b), "readout belief is not finite");
    sum += b;
  }
  if (tree.rule().uncertaintyIsMass()) {
    require(o.uncertainty >= 0.0f && o.uncertainty <= 1.0f, "readout uncertainty outside [0, 1]");
    for (float b : o.belief) require(b >= 0.0f && b <= 1.0f, "readout belief outside [0, 1]");
    require(std::fabs(sum - 1.0) <= 1e-4, "readout: sum(b) + u != 1");
  }
}

std::string writeOt(const octomap::AbstractOcTree& tree) {
  std::ostringstream out;
  out << std::setprecision(17);  // AbstractOcTree::write prints `res` with the stream precision
  tree.write(out);
  return out.str();
}

// Reads bytes that one of our own writers produced: must succeed and be our tree.
std::unique_ptr<EvidentialOcTree> readOwnOutput(const std::string& bytes, const char* what) {
  std::istringstream in(bytes);
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(in));
  auto* tree = dynamic_cast<EvidentialOcTree*>(any.get());
  require(tree != nullptr, std::string(what) + ": our own output is not read back as our tree");
  require(tree->readError().empty(),
          std::string(what) + ": our own output is rejected: " + tree->readError());
  require(!in.fail(), std::string(what) + ": our own output leaves the stream failed");
  any.release();
  return std::unique_ptr<EvidentialOcTree>(tree);
}

void exercise(EvidentialOcTree& tree, bool heavy) {
  const int num_classes = tree.numClasses();
  require(num_classes >= 1 && num_classes <= EvidentialOcTree::kMaxClasses, "class count");
  require(static_cast<int>(tree.classNames().size()) == num_classes, "class name count");
  require(tree.calcNumNodes() == tree.size(), "size() disagrees with the node count");
  // A read map has parameters the library accepts (a resealed file once loaded clamps 0.5+).
  require(tree.parameterProblem().empty(), "read with bad parameters: " + tree.parameterProblem());
  (void)tree.memoryUsage();

  // Every node (inner ones too), every leaf, queries by key and by coordinate.
  size_t semantic = 0;
  for (auto it = tree.begin_tree(), end = tree.end_tree(); it != end; ++it) {
    checkOpinion(tree, &*it, "as read");
    if (it.isLeaf() && it->hasSemantics()) ++semantic;  // inner nodes name a leaf's payload
  }
  require(semantic == tree.numSemanticNodes(), "numSemanticNodes() disagrees with the leaves");
  checkOpinion(tree, nullptr, "prior");
  size_t leaves = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end && leaves < 4096;
       ++it, ++leaves) {
    (void)tree.isNodeOccupied(*it);
    const octomap::point3d centre = it.getCoordinate();
    require(std::isfinite(centre.x()) && std::isfinite(centre.y()) && std::isfinite(centre.z()),
            "a voxel centre is not finite (resolution out of range)");
    const VoxelOpinion by_key = tree.query(it.getKey(), it.getDepth());
    const VoxelOpinion direct = tree.opinion(&*it);
    require(by_key.label == direct.label, "query(key, depth) disagrees with the iterator's node");
    (void)tree.query(it.getCoordinate());
  }
  (void)tree.query(octomap::point3d(0.f, 0.f, 0.f));

  // Round trip: our writer, our reader, byte-identical second write, same resolution. Through
  // loadMap always; through AbstractOcTree::read only for non-empty trees, because OctoMap's
  // generic reader skips the data section (and so our semantic header) when "size" is 0.
  const std::string first = writeOt(tree);
  {
    const MemFile file(reinterpret_cast<const uint8_t*>(first.data()), first.size());
    std::unique_ptr<EvidentialOcTree> loaded;
    try {
      loaded = loadMap(file.path());
    } catch (const std::exception& e) {
      fuzzFail(std::string("loadMap rejects our own output: ") + e.what());
    }
    require(writeOt(*loaded) == first, "write -> loadMap -> write is not byte-identical");
    require(loaded->getResolution() == tree.getResolution(), "loadMap changed the resolution");
  }
  if (tree.size() > 0) {
    const auto again = readOwnOutput(first, "round trip");
    require(writeOt(*again) == first, "write -> read -> write is not byte-identical");
    require(again->getResolution() == tree.getResolution(), "round trip changed the resolution");
  }

  // The copy constructor and then the edits the integrator does.
  EvidentialOcTree copy(tree);
  require(writeOt(copy) == first, "copy constructor changed the map");
  detail::TreeEditing::updateInnerNodes(copy);
  detail::TreeEditing::compactPayloads(copy);
  for (auto it = copy.begin_tree(), end = copy.end_tree(); it != end; ++it) {
    checkOpinion(copy, &*it, "after updateInnerNodes");
  }

  // Merging a map into a copy of itself.
  copy.merge(tree);
  for (auto it = copy.begin_tree(), end = copy.end_tree(); it != end; ++it) {
    checkOpinion(copy, &*it, "after merge");
  }

  // Occupancy-only .bt and the ColorOcTree export.
  std::ostringstream bt;
  tree.writeBinaryConst(bt);
  std::istringstream bt_in(bt.str());
  octomap::OcTree plain(0.1);
  require(plain.readBinary(bt_in), "our .bt is not readable by octomap::OcTree");
  ClassTable classes;
  for (int c = 0; c < num_classes; ++c) {
    classes.names.push_back(tree.classNames()[c]);
    classes.colors.push_back({uint8_t(c), uint8_t(255 - c), 128});
  }
  (void)toColorOcTree(tree, classes, tree.size() % 2 ? ColorMode::kClass : ColorMode::kUncertainty);

  // One small scan into the loaded map: a loaded map is a map that gets more scans. Costly
  // (ray casting buffers, kernel tables), so done for one input in four, chosen by its bytes.
  if (!heavy) return;
  SemanticConfig one_thread = copy.config();
  one_thread.threads = 1;  // no thread team per input
  copy.setConfig(one_thread);
  const std::string copy_before_scan = writeOt(copy);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (int i = 0; i < 4; ++i) {
    points.push_back(0.5f * i, 0.3f, -0.2f * i);
    for (int c = 0; c < num_classes; ++c) evidence.push_back(c == i % num_classes ? 5.0f : 0.1f);
  }
  // A file may hold a kernel no scan may use (beyond SemanticConfig::kMaxSupportLeaves): then
  // the scan is refused before anything changes.
  const std::string support = copy.config().supportProblem(copy.getResolution());
  try {
    copy.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.5f));
    require(support.empty(), "a scan with an unaffordable kernel was run");
  } catch (const std::invalid_argument& e) {
    require(!support.empty(), std::string("a scan was refused: ") + e.what());
    require(writeOt(copy) == copy_before_scan, "a refused scan changed the map");
  }
  for (auto it = copy.begin_tree(), end = copy.end_tree(); it != end; ++it) {
    checkOpinion(copy, &*it, "after insertSemanticScan");
  }
}

}  // namespace

void fuzzFail(const std::string& what) {
  const std::string message = "\nFUZZ INVARIANT BROKEN: " + what + "\n";
  if (::write(g_report_fd, message.data(), message.size()) < 0) std::perror("write");
  // Under libFuzzer with -close_fd_mask=2, fd 2 is closed: the sanitizer's report fd is not.
  if (__sanitizer_report_error_summary) __sanitizer_report_error_summary(message.c_str());
  std::abort();
}

void setAlwaysHeavy(bool always) { g_always_heavy = always; }

void resealOtChecksum(uint8_t* data, size_t size) {
  static const uint8_t kData[] = {'\n', 'd', 'a', 't', 'a', '\n', 'E', 'V', 'E', 'M'};
  const uint8_t* end = data + size;
  const uint8_t* at =
      std::search(static_cast<const uint8_t*>(data), end, kData, kData + sizeof(kData));
  if (at == end) return;
  const size_t section = static_cast<size_t>(at - data) + 6;
  uint32_t format = 0;
  if (size < section + 8 + 4) return;
  std::memcpy(&format, data + section + 4, 4);
  if (format < 2) return;  // format 1 has no checksum
  const uint32_t crc = crc32Update(0, data + section, size - 4 - section);
  std::memcpy(data + size - 4, &crc, 4);
}

void silenceStderr() {
  const int saved = ::dup(2);
  const int devnull = ::open("/dev/null", O_WRONLY);
  if (saved < 0 || devnull < 0) return;
  std::fflush(stderr);
  ::dup2(devnull, 2);
  ::close(devnull);
  g_report_fd = saved;
  if (__sanitizer_set_report_fd)
    __sanitizer_set_report_fd(reinterpret_cast<void*>(intptr_t(saved)));
  // An exception escaping a target: say which, on the stderr that is still open.
  std::set_terminate([] {
    std::string what = "unknown exception";
    try {
      if (auto e = std::current_exception()) std::rethrow_exception(e);
    } catch (const std::exception& e) {
      what = std::string(typeid(e).name()) + ": " + e.what();
    } catch (...) {
    }
    fuzzFail("uncaught exception escaped the library: " + what);
  });
}

void silenceDiagnostics() {
  static std::ostringstream sink;
  sink.setstate(std::ios::badbit);  // discards everything written to it
  std::cerr.rdbuf(sink.rdbuf());
  std::clog.rdbuf(sink.rdbuf());
}

int fuzzOtReader(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);

  // 1. The generic OctoMap reader, as any program that links the library calls it. Files of
  //    OctoMap's own types go to OctoMap's readers, which are not ours to fuzz (they trust
  //    their input: no depth limit, see docs/experiments/reliability.md); loadMap below still gets
  //    them.
  const OtHeader header = OtHeaderReader::parse(bytes);
  bool generic_ok = false;
  if (header.id == "EvidentialOcTree") {
    std::istringstream in(bytes);
    std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(in));
    auto* tree = dynamic_cast<EvidentialOcTree*>(any.get());
    if (tree) {
      if (!tree->readError().empty()) {
        // A failed read leaves the tree empty (documented in evidential_octree.h).
        require(tree->size() == 0 && tree->getRoot() == nullptr && tree->numSemanticNodes() == 0,
                "a failed read left nodes behind");
        require(in.fail(), "a failed read did not fail the stream");
      } else if (!in.fail() && header.size > 0) {
        // (With "size 0" OctoMap never calls readData: the tree is a default one with whatever
        // resolution the header says, unchecked. Only loadMap's answer counts for those files.)
        generic_ok = true;
        uint32_t hash = 2166136261u;  // FNV-1a of the input picks the inputs that insert a scan
        for (size_t i = 0; i < size; ++i) hash = (hash ^ data[i]) * 16777619u;
        exercise(*tree, g_always_heavy || hash % 4 == 0);
      }
    }
  }

  // 2. loadMap on the same bytes as a file: the same verdict, errors only as runtime_error.
  MemFile file(data, size);
  bool load_ok = false;
  try {
    std::unique_ptr<EvidentialOcTree> tree = loadMap(file.path());
    require(tree != nullptr, "loadMap returned nullptr instead of throwing");
    load_ok = true;
  } catch (const std::runtime_error& e) {
    require(std::strlen(e.what()) > 0, "loadMap threw an empty message");
  }
  // With "size 0" AbstractOcTree::read reads no data at all, so only files that announce nodes
  // are comparable.
  if (header.size > 0) {
    require(generic_ok == load_ok, generic_ok
                                       ? "loadMap rejects what AbstractOcTree::read accepts"
                                       : "loadMap accepts what AbstractOcTree::read rejects");
  }
  return 0;
}

namespace {

// Values from the input: mostly raw bits, sometimes one of the values that break arithmetic.
struct ByteReader {
  const uint8_t* data;
  size_t size, at = 0;
  bool done() const { return at >= size; }
  uint8_t byte() { return at < size ? data[at++] : 0; }
  double number() {
    static const double kSpecial[] = {std::nan(""), INFINITY, -INFINITY, 1e30,   -1e30,
                                      3.4e38,       0.0,      -0.0,      1e-300, 1.0,
                                      0.5,          0.999,    0.001,     1e300};
    const uint8_t kind = byte();
    if (kind < 48) return kSpecial[kind % (sizeof(kSpecial) / sizeof(kSpecial[0]))];
    float value = 0.f;  // four raw bytes as a float
    for (int i = 0; i < 4; ++i) reinterpret_cast<uint8_t*>(&value)[i] = byte();
    return kind < 160 ? double(value) : double(kind - 160) / 8.0 - 4.0;  // or a small number
  }
  octomap::point3d point() {
    const double x = number(), y = number(), z = number();
    return octomap::point3d(float(x), float(y), float(z));
  }
};

// The map every input starts from: one scan of a wall and a floor, C = 3.
const EvidentialOcTree& servicesBaseMap() {
  static const std::unique_ptr<EvidentialOcTree> base = [] {
    SemanticConfig config;
    config.threads = 1;
    auto tree = std::make_unique<EvidentialOcTree>(0.2, 3, config);
    octomap::Pointcloud points;
    std::vector<float> evidence;
    for (float y = -1.f; y <= 1.f; y += 0.25f) {
      for (float z = -0.5f; z <= 0.5f; z += 0.25f) {
        points.push_back(3.f, y, z);
        evidence.insert(evidence.end(), {9.f, 1.f, 0.f});
      }
      points.push_back(1.5f, y, -1.f);
      evidence.insert(evidence.end(), {0.f, 2.f, 12.f});
    }
    tree->insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.f));
    return tree;
  }();
  return *base;
}

void checkWholeMap(const EvidentialOcTree& tree, const char* stage) {
  for (auto it = tree.begin_tree(), end = tree.end_tree(); it != end; ++it) {
    checkOpinion(tree, &*it, stage);
  }
}

}  // namespace

int fuzzMapServices(const uint8_t* data, size_t size) {
  EvidentialOcTree tree(servicesBaseMap());
  ByteReader in{data, size};
  for (int op = 0; op < 16 && !in.done(); ++op) {
    const std::string before = writeOt(tree);
    switch (in.byte() % 5) {
      case 0: {  // ~query
        const octomap::point3d p = in.point();
        const EvidentialOcTreeNode* node = tree.nodeAt(p);
        const bool finite = std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
        require(finite || node == nullptr, "nodeAt found a node for a non-finite point");
        checkOpinion(tree, node, "query");
        const VoxelOpinion o = tree.query(p);
        // Unknown space has no answer; a voxel with evidence answers its own; a known voxel
        // without any may answer from the evidence around it (query_support.cpp).
        const bool own = node == nullptr || node->hasSemantics();
        require(!own || o.label == tree.opinion(node).label, "query(point) disagrees with nodeAt");
        require(o.label >= -1 && o.label < tree.numClasses(), "query(point) label out of range");
        break;
      }
      case 1: {  // ~clear_bbx
        const octomap::point3d min = in.point(), max = in.point();
        const std::string problem = boxProblem(min, max);
        try {
          clearBox(&tree, min, max);
          require(problem.empty(), "clearBox accepted a box boxProblem refuses: " + problem);
        } catch (const std::invalid_argument&) {
          require(!problem.empty(), "clearBox refused a box boxProblem accepts");
          require(writeOt(tree) == before, "a refused clearBox changed the map");
        }
        break;
      }
      case 2: {  // ~sensor_model/* and its dynamic_reconfigure ranges
        SensorModel model{in.number(), in.number(), in.number(), in.number(), in.number()};
        try {
          tree.setSensorModel(model);
          require(model.problem().empty(), "setSensorModel accepted " + model.problem());
        } catch (const std::invalid_argument&) {
          require(!model.problem().empty(), "setSensorModel refused a valid model");
          require(writeOt(tree) == before, "a refused sensor model changed the map");
        }
        break;
      }
      case 3: {  // kernel ~params / dynamic_reconfigure, then a scan
        SemanticConfig config = tree.config();
        config.length_scale = in.number();
        config.beta = in.number();
        config.gamma = in.number();
        config.sigma0 = in.number();
        config.drop_percent = in.number();
        config.ds_multiplier = in.number();
        config.max_range = in.number();
        config.threads = 1;
        try {
          tree.setConfig(config);
        } catch (const std::invalid_argument&) {
          require(!config.problem().empty(), "setConfig refused a valid config");
          require(writeOt(tree) == before, "a refused config changed the map");
          break;
        }
        const std::string configured = writeOt(tree);
        octomap::Pointcloud points;
        points.push_back(in.point());
        points.push_back(2.f, 0.5f, 0.f);
        const std::vector<float> evidence{float(std::fabs(in.number())), 1.f, 0.f, 0.f, 0.f, 3.f};
        const bool evidence_ok = std::isfinite(evidence[0]);
        const std::string affordable = config.supportProblem(tree.getResolution());
        try {
          tree.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.2f));
          require(affordable.empty() && evidence_ok, "a scan that should be refused was run");
        } catch (const std::invalid_argument&) {
          require(!affordable.empty() || !evidence_ok, "an affordable, valid scan was refused");
          require(writeOt(tree) == configured, "a refused scan changed the map");
        }
        break;
      }
      default: {  // ~save_map then ~load_map
        const std::string bytes = writeOt(tree);
        const MemFile file(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
        std::unique_ptr<EvidentialOcTree> loaded;
        try {
          loaded = loadMap(file.path());
        } catch (const std::exception& e) {
          fuzzFail(std::string("a map the services made does not load: ") + e.what());
        }
        require(writeOt(*loaded) == bytes, "save -> load -> save is not byte-identical");
        break;
      }
    }
    checkWholeMap(tree, "after a service call");
  }
  return 0;
}

int fuzzClassTable(const uint8_t* data, size_t size) {
  MemFile file(data, size);
  try {
    const ClassTable table = ClassTable::load(file.path());
    const int n = table.numClasses();
    require(n >= 1 && n <= EvidentialOcTree::kMaxClasses, "class table: class count");
    require(table.colors.size() == table.names.size(), "class table: colours != names");
    require(table.ignore_class >= -1 && table.ignore_class < n, "class table: ignore_class");
    for (const auto& [raw, cls] : table.learning_map) {
      require(cls >= 0 && cls < n, "class table: learning_map target out of range");
      require(table.classOfRaw(raw) == cls || (raw & 0xFFFFu) != raw,
              "class table: classOfRaw disagrees with learning_map");
    }
  } catch (const std::runtime_error& e) {
    require(std::strlen(e.what()) > 0, "class table: empty error message");
  } catch (const std::out_of_range&) {
    // classOfRaw of a raw id above 16 bits: documented std::out_of_range.
  }
  return 0;
}

}  // namespace fuzz
}  // namespace evidential_octomap
