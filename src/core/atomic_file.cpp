// writeFileAtomically (io.h): unique temporary, lock, fsync, rename, fsync of the directory, and
// removal of the temporaries that killed writers left behind.
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "evidential_octomap/io.h"

namespace evidential_octomap {
namespace {

// `<name>` + kTempInfix + 6 characters from mkstemp.
constexpr char kTempInfix[] = ".evidential-tmp.";

std::string errnoText() { return std::strerror(errno); }

struct SplitPath {
  std::string dir;   // "." for a bare file name
  std::string name;  // last component
};
SplitPath splitPath(const std::string& path) {
  const size_t slash = path.rfind('/');
  if (slash == std::string::npos) return {".", path};
  return {slash == 0 ? "/" : path.substr(0, slash), path.substr(slash + 1)};
}

bool sameFile(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

// The mode a plain open(O_CREAT, 0666) would give: 0666 minus the process umask.
mode_t defaultFileMode() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.compare(0, 6, "Umask:") == 0) return 0666 & ~mode_t(std::stoul(line.substr(6), 0, 8));
  }
  return 0644;
}

// A temporary beside the target, created, locked and verified to still be ours (a cleaner in
// another process may have removed it between mkstemp and flock).
struct Temporary {
  std::string path;
  int fd = -1;
};
Temporary createLockedTemporary(const std::string& target) {
  for (int attempt = 0; attempt < 8; ++attempt) {
    std::string pattern = target + kTempInfix + "XXXXXX";
    const int fd = ::mkstemp(&pattern[0]);
    if (fd < 0) throw std::runtime_error("cannot write " + target + ": " + errnoText());
    struct stat by_fd, by_path;
    if (::flock(fd, LOCK_EX) == 0 && ::fstat(fd, &by_fd) == 0 &&
        ::stat(pattern.c_str(), &by_path) == 0 && sameFile(by_fd, by_path)) {
      ::fchmod(fd, defaultFileMode());
      return {pattern, fd};
    }
    ::close(fd);
  }
  throw std::runtime_error("cannot write " + target + ": temporary files keep disappearing");
}

void fsyncDirectory(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;  // best effort: the rename itself has happened
  ::fsync(fd);
  ::close(fd);
}

// Removes `entry` if it is a temporary of ours whose writer is gone (its lock is free).
void removeIfAbandoned(const std::string& entry) {
  const int fd = ::open(entry.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK);
  if (fd < 0) return;
  struct stat by_fd, by_path;
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::fstat(fd, &by_fd) == 0 && S_ISREG(by_fd.st_mode) &&
      ::stat(entry.c_str(), &by_path) == 0 && sameFile(by_fd, by_path)) {
    ::unlink(entry.c_str());  // still holding the lock: no writer can have taken it over
  }
  ::close(fd);
}

// `<name>.tmp.<pid>`, the temporaries of library versions before the lock: removed when that
// process no longer exists.
bool isLegacyTemporaryOfDeadWriter(const std::string& name, const std::string& target_name) {
  const std::string prefix = target_name + ".tmp.";
  if (name.compare(0, prefix.size(), prefix) != 0) return false;
  const std::string pid = name.substr(prefix.size());
  if (pid.empty() || pid.size() > 9 || pid.find_first_not_of("0123456789") != std::string::npos) {
    return false;
  }
  return ::kill(static_cast<pid_t>(std::stol(pid)), 0) != 0 && errno == ESRCH;
}

bool isOurTemporaryName(const std::string& name) {
  const size_t infix = sizeof(kTempInfix) - 1;
  return name.size() > infix + 6 && name.compare(name.size() - infix - 6, infix, kTempInfix) == 0;
}

void removeAbandonedTemporaries(const SplitPath& target) {
  DIR* dir = ::opendir(target.dir.c_str());
  if (!dir) return;  // best effort: the save itself has succeeded
  std::vector<std::string> abandoned;
  while (const dirent* e = ::readdir(dir)) {
    const std::string name = e->d_name;
    if (isOurTemporaryName(name) || isLegacyTemporaryOfDeadWriter(name, target.name)) {
      abandoned.push_back(target.dir + "/" + name);
    }
  }
  ::closedir(dir);
  for (const std::string& entry : abandoned) {
    if (isOurTemporaryName(splitPath(entry).name)) {
      removeIfAbandoned(entry);
    } else {
      ::unlink(entry.c_str());
    }
  }
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::function<bool(std::ostream&)>& write) {
  if (path.empty()) throw std::runtime_error("cannot write a file with an empty path");
  const Temporary temp = createLockedTemporary(path);
  const auto fail = [&](const std::string& why) {
    ::unlink(temp.path.c_str());
    ::close(temp.fd);
    throw std::runtime_error(why);
  };
  {
    std::ofstream out(temp.path, std::ios::binary | std::ios::trunc);
    if (!out) fail("cannot write " + path + ": " + errnoText());
    bool ok = false;
    errno = 0;
    try {
      ok = write(out) && out.flush().good();
    } catch (const std::exception& e) {
      fail("writing " + path + " failed: " + e.what());
    }
    int write_errno = ok ? 0 : errno;
    out.close();
    if (ok && out.fail()) write_errno = errno;
    if (!ok || out.fail()) {
      // The stream keeps no error code; the errno of its failed write(2) is the reason when it
      // is one a write gives (a full disk, a file size limit, an I/O error, a quota).
      if (write_errno == ENOSPC || write_errno == EFBIG || write_errno == EIO ||
          write_errno == EDQUOT || write_errno == EROFS) {
        fail("writing " + path + " failed: " + std::strerror(write_errno) +
             "; the previous file, if any, is unchanged");
      }
      fail("writing " + path + " failed (disk full, or the data refused); the previous file, if " +
           "any, is unchanged");
    }
  }
  // The bytes are durable before the rename makes them visible, and the rename before we return.
  if (::fsync(temp.fd) != 0) {
    fail("writing " + path + " failed: fsync: " + errnoText() +
         "; the previous file, if any, is unchanged");
  }
  if (::rename(temp.path.c_str(), path.c_str()) != 0) {
    fail("cannot replace " + path + ": " + errnoText());
  }
  ::close(temp.fd);
  const SplitPath target = splitPath(path);
  fsyncDirectory(target.dir);
  removeAbandonedTemporaries(target);
}

void writeFileAtomically(const std::string& path, const std::string& bytes) {
  writeFileAtomically(path, [&](std::ostream& out) {
    return static_cast<bool>(out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())));
  });
}

void linkOrCopyFile(const std::string& from, const std::string& to) {
  ::unlink(to.c_str());
  if (::link(from.c_str(), to.c_str()) == 0) return;
  if (errno != EXDEV && errno != EPERM && errno != EMLINK)
    throw std::runtime_error("cannot link " + from + " to " + to + ": " + errnoText());
  std::ifstream in(from, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + from + ": " + errnoText());
  writeFileAtomically(to, [&](std::ostream& out) { return static_cast<bool>(out << in.rdbuf()); });
}

}  // namespace evidential_octomap
