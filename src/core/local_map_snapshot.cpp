#include "evidential_octomap/local_map_snapshot.h"

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "evidential_octomap/io.h"

namespace evidential_octomap {

namespace fs = std::filesystem;

namespace {
constexpr char kSnapshotPrefix[] = "snapshot_";
constexpr char kStagingPrefix[] = "staging_";

// n of snapshot_<n>, or -1 for any other name.
long snapshotNumber(const fs::path& p) {
  const std::string name = p.filename().string();
  const size_t prefix = sizeof(kSnapshotPrefix) - 1;
  if (name.rfind(kSnapshotPrefix, 0) != 0 || name.size() == prefix) return -1;
  for (size_t i = prefix; i < name.size(); ++i)
    if (name[i] < '0' || name[i] > '9') return -1;
  return std::stol(name.substr(prefix));
}

void fsyncDirectory(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;  // best effort: the entries exist either way
  ::fsync(fd);
  ::close(fd);
}

long newestNumber(const fs::path& base) {
  long newest = -1;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(base, ec))
    newest = std::max(newest, snapshotNumber(entry.path()));
  return newest;
}
}  // namespace

std::string stageLocalMapSnapshot(const LocalMap& map, const std::string& base) {
  std::error_code ec;
  fs::create_directories(base, ec);
  if (ec) throw std::runtime_error("cannot make " + base + ": " + ec.message());
  const fs::path staging = fs::path(base) / (kStagingPrefix + std::to_string(::getpid()));
  fs::remove_all(staging, ec);
  fs::create_directory(staging, ec);
  if (ec) throw std::runtime_error("cannot make " + staging.string() + ": " + ec.message());
  try {
    for (const std::string& tile : map.tileFiles())
      linkOrCopyFile(tile, (staging / fs::path(tile).filename()).string());
  } catch (...) {
    fs::remove_all(staging, ec);
    throw;
  }
  return staging.string();
}

std::string commitLocalMapSnapshot(const std::string& staging, const std::string& resident_bytes,
                                   const std::string& base) {
  const fs::path target = fs::path(base) / (kSnapshotPrefix + std::to_string(newestNumber(base) + 1));
  std::error_code ec;
  try {
    // Its directory fsync also makes the tiles' links durable before the rename publishes them.
    writeFileAtomically((fs::path(staging) / "resident.ot").string(), resident_bytes);
    fs::rename(staging, target);
  } catch (const std::exception&) {
    fs::remove_all(staging, ec);
    throw;
  }
  fsyncDirectory(base);
  for (const auto& entry : fs::directory_iterator(base, ec)) {
    const long n = snapshotNumber(entry.path());
    if (n >= 0 && entry.path() != target) fs::remove_all(entry.path(), ec);
  }
  return target.string();
}

LocalMapSnapshot newestLocalMapSnapshot(const std::string& base) {
  LocalMapSnapshot snapshot;
  std::error_code ec;
  if (!fs::is_directory(base, ec)) return snapshot;
  for (const auto& entry : fs::directory_iterator(base, ec)) {
    if (entry.path().filename().string().rfind(kStagingPrefix, 0) == 0)
      fs::remove_all(entry.path(), ec);  // a killed writer's, never complete
  }
  const long n = newestNumber(base);
  if (n < 0) return snapshot;
  const fs::path dir = fs::path(base) / (kSnapshotPrefix + std::to_string(n));
  snapshot.directory = dir.string();
  snapshot.resident = (dir / "resident.ot").string();
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("tile_", 0) == 0 && entry.path().extension() == ".ot")
      snapshot.tiles.push_back(entry.path().string());
  }
  return snapshot;
}

}  // namespace evidential_octomap
