// Saves and exports into a full filesystem, past a file-size limit and into a read-only
// filesystem: every writer (.ot, .bt, ColorOcTree export, PNG, JSON / Markdown reports) fails
// with a clear std::runtime_error naming the path and the reason, keeps the previous file byte
// for byte and leaves no temporary behind; the next write that fits succeeds.
//
// The file-size limit (RLIMIT_FSIZE, in a forked child) runs for every user. The full and the
// read-only filesystem are a small tmpfs mounted by the test when it may mount (root in a
// container with CAP_SYS_ADMIN); otherwise the full case is skipped with the reason and the
// read-only case uses a directory without write permission (which root would ignore).
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "render.h"
#include "report.h"
#include "test_helpers.h"

namespace evidential_octomap {
namespace {

namespace fs = std::filesystem;

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

const ClassTable& kittiTable() {
  static const ClassTable table = ClassTable::load(tools_test::kittiClasses());
  return table;
}

// A dense block of side^3 semantic leaves with random payloads (C of the KITTI table).
std::unique_ptr<EvidentialOcTree> blockMap(int side, unsigned seed) {
  const int c = kittiTable().numClasses();
  auto tree = std::make_unique<EvidentialOcTree>(0.1, c);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, 40.0f);
  const octomap::OcTreeKey origin = tree->coordToKey(octomap::point3d(0.f, 0.f, 0.f));
  std::vector<float> payload(c);
  for (int x = 0; x < side; ++x)
    for (int y = 0; y < side; ++y)
      for (int z = 0; z < side; ++z) {
        EvidentialOcTreeNode* leaf =
            detail::TreeEditing::leafForUpdate(*tree, octomap::OcTreeKey(origin[0] + x, origin[1] + y, origin[2] + z),
                                true);
        leaf->setLogOdds(value(rng) / 20.0f - 1.0f + 0.01f * float(x));
        for (float& v : payload) v = value(rng);
        detail::TreeEditing::setPayload(*tree, leaf, payload.data());
      }
  detail::TreeEditing::updateInnerNodes(*tree);
  return tree;
}

// One writer of the project: writes a small file (a few KiB) or a large one (> 200 KiB).
struct Writer {
  const char* name;
  std::function<void(const std::string& path, bool large)> write;
};

const EvidentialOcTree& mapOfSize(bool large) {
  static const auto small_map = blockMap(3, 1);
  static const auto large_map = blockMap(16, 2);
  return large ? *large_map : *small_map;
}

const std::vector<Writer>& writers() {
  static const std::vector<Writer> all = {
      {"ot", [](const std::string& p, bool large) { saveMap(mapOfSize(large), p); }},
      {"bt",
       [](const std::string& p, bool large) {
         // .bt holds occupancy only (2 bits a node): a deeper block for the large file.
         static const auto huge = blockMap(48, 3);
         saveBinaryOccupancy(large ? *huge : mapOfSize(false), p);
       }},
      {"color_octree",
       [](const std::string& p, bool large) {  // what `evidential_octomap export` writes
         const auto color = toColorOcTree(mapOfSize(large), kittiTable(), ColorMode::kClass);
         writeFileAtomically(p, [&](std::ostream& out) { return color->write(out) && out.good(); });
       }},
      {"png",
       [](const std::string& p, bool large) {
         cv::Mat image(large ? 300 : 16, large ? 300 : 16, CV_8UC3);
         cv::randu(image, 0, 255);  // noise: PNG cannot compress it
         tools::writePng(p, image);
       }},
      {"json_report",
       [](const std::string& p, bool large) {
         std::string json = "{\"rows\": [";
         for (int i = 0; i < (large ? 12000 : 10); ++i) json += "{\"iou\": 0.123456789},";
         json += "{}]}\n";
         tools::writeText(p, json);
       }},
  };
  return all;
}

std::vector<std::string> filesIn(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  return names;
}

// The writer's large file into `path` must fail with a runtime_error naming the path and
// `reason`; the previous file stays byte-identical and no temporary is left in the directory.
void expectRefusedKeepingOldFile(const Writer& w, const std::string& path,
                                 const std::string& before, const std::string& reason,
                                 const std::function<void()>& attempt) {
  std::string message;
  try {
    attempt();
  } catch (const std::runtime_error& e) {
    message = e.what();
  }
  ASSERT_FALSE(message.empty()) << w.name << ": the write into " << path << " did not fail";
  std::cout << "[" << w.name << "] " << message << "\n";
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find(reason), std::string::npos) << "no reason \"" << reason << "\" in: "
                                                     << message;
  EXPECT_TRUE(readFile(path) == before) << w.name << ": the previous file changed";
  for (const std::string& f : filesIn(fs::path(path).parent_path().string())) {
    EXPECT_EQ(f.find(".evidential-tmp."), std::string::npos) << "temporary left behind: " << f;
  }
}

// A tmpfs of `kib` KiB mounted on a fresh directory, unmounted at the end; empty path when this
// process may not mount (then `why` says why).
struct Tmpfs {
  std::string path, why;
  explicit Tmpfs(const std::string& name, int kib) {
    const std::string dir = tools_test::freshDir(name);
    const std::string options = "size=" + std::to_string(kib) + "k";
    if (::mount("tmpfs", dir.c_str(), "tmpfs", 0, options.c_str()) == 0) {
      path = dir;
    } else {
      why = std::string("cannot mount a tmpfs here: ") + std::strerror(errno);
    }
  }
  ~Tmpfs() {
    if (!path.empty()) ::umount2(path.c_str(), MNT_DETACH);
  }
};

class DiskFailures : public ::testing::TestWithParam<size_t> {
 protected:
  const Writer& writer() const { return writers()[GetParam()]; }
};

// A file-size limit below the new file: write(2) fails with EFBIG (SIGXFSZ ignored). In a
// forked child, so the limit never reaches the test runner; root does not bypass it.
TEST_P(DiskFailures, FileSizeLimitKeepsThePreviousFileAndNoTemporary) {
  const Writer& w = writer();
  const std::string dir = tools_test::freshDir(std::string("fsize_") + w.name);
  const std::string path = dir + "/out." + w.name;
  w.write(path, false);
  const std::string before = readFile(path);
  ASSERT_FALSE(before.empty());
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(pipe_fds[0]);
    ::signal(SIGXFSZ, SIG_IGN);
    struct rlimit limit;
    ::getrlimit(RLIMIT_FSIZE, &limit);
    limit.rlim_cur = before.size() + 8192;
    ::setrlimit(RLIMIT_FSIZE, &limit);
    int code = 1;  // 1: no error; 0: runtime_error (its message in the pipe); 2: another error
    std::string message;
    try {
      w.write(path, true);
    } catch (const std::runtime_error& e) {
      code = 0;
      message = e.what();
    } catch (...) {
      code = 2;
    }
    if (::write(pipe_fds[1], message.data(), message.size()) < 0) code = 3;
    ::close(pipe_fds[1]);
    ::_exit(code);
  }
  ::close(pipe_fds[1]);
  std::string message;
  char buffer[512];
  ssize_t got;
  while ((got = ::read(pipe_fds[0], buffer, sizeof(buffer))) > 0) message.append(buffer, got);
  ::close(pipe_fds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the writer died (signal " << WTERMSIG(status) << ")";
  ASSERT_EQ(WEXITSTATUS(status), 0) << w.name << ": 1 = the large write succeeded, 2 = not a "
                                                 "runtime_error";
  std::cout << "[" << w.name << "] " << message << "\n";
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find(std::strerror(EFBIG)), std::string::npos) << message;
  EXPECT_TRUE(readFile(path) == before) << "the previous file changed";
  for (const std::string& f : filesIn(dir)) {
    EXPECT_EQ(f.find(".evidential-tmp."), std::string::npos) << "temporary left behind: " << f;
  }
  EXPECT_NO_THROW(w.write(path, true));  // without the limit it fits
}

// A nearly full filesystem: the previous file, a filler taking all but ~16 KiB, then the large
// write: ENOSPC, old file kept, no temporary; once the filler is gone the same write succeeds.
TEST_P(DiskFailures, NearlyFullFilesystemKeepsThePreviousFileAndNoTemporary) {
  const Writer& w = writer();
  Tmpfs tmpfs(std::string("full_") + w.name, 512);
  if (tmpfs.path.empty()) GTEST_SKIP() << tmpfs.why << " (the file-size-limit case still runs)";
  const std::string path = tmpfs.path + "/out." + w.name;
  w.write(path, false);
  const std::string before = readFile(path);
  const std::string filler = tmpfs.path + "/filler";
  {
    std::ofstream out(filler, std::ios::binary);
    const std::string block(4096, 'x');
    while (out.write(block.data(), block.size()) && out.flush()) {
    }
  }
  fs::resize_file(filler, fs::file_size(filler) - 16 * 1024);  // leave ~16 KiB free
  expectRefusedKeepingOldFile(w, path, before, std::strerror(ENOSPC),
                              [&] { w.write(path, true); });
  fs::remove(filler);
  EXPECT_NO_THROW(w.write(path, true));
}

// A read-only filesystem (root: a tmpfs remounted read-only; else a directory without write
// permission): the write fails at once, old file kept, nothing created.
TEST_P(DiskFailures, ReadOnlyFilesystemKeepsThePreviousFileAndNoTemporary) {
  const Writer& w = writer();
  Tmpfs tmpfs(std::string("ro_") + w.name, 4096);
  std::string dir = tmpfs.path, reason = std::strerror(EROFS);
  if (dir.empty()) {
    if (::geteuid() == 0) GTEST_SKIP() << tmpfs.why << "; as root a read-only directory is no test";
    dir = tools_test::freshDir(std::string("ro_dir_") + w.name);
    reason = std::strerror(EACCES);
  }
  const std::string path = dir + "/out." + w.name;
  w.write(path, false);
  const std::string before = readFile(path);
  if (!tmpfs.path.empty()) {
    ASSERT_EQ(::mount(nullptr, dir.c_str(), nullptr, MS_REMOUNT | MS_RDONLY, nullptr), 0)
        << std::strerror(errno);
  } else {
    ASSERT_EQ(::chmod(dir.c_str(), 0555), 0);
  }
  expectRefusedKeepingOldFile(w, path, before, reason, [&] { w.write(path, true); });
  expectRefusedKeepingOldFile(w, path, before, reason, [&] { w.write(path, false); });
  if (tmpfs.path.empty()) ::chmod(dir.c_str(), 0755);
}

INSTANTIATE_TEST_SUITE_P(AllWriters, DiskFailures, ::testing::Range<size_t>(0, 5),
                         [](const ::testing::TestParamInfo<size_t>& info) {
                           return std::string(writers()[info.param].name);
                         });

}  // namespace
}  // namespace evidential_octomap
