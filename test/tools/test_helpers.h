// Shared by the tool tests: paths (CMake-defined) and temporary directories.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace tools_test {

inline std::string dataDir() { return EVIDENTIAL_TEST_DATA_DIR; }
inline std::string kittiDir() { return dataDir() + "/semantickitti_08_first10"; }
inline std::string rellisDir() { return dataDir() + "/rellis3d_example_000104"; }
inline std::string kittiClasses() {
  return std::string(EVIDENTIAL_TEST_CONFIG_DIR) + "/classes_semantickitti.yaml";
}
inline std::string rellisClasses() {
  return std::string(EVIDENTIAL_TEST_CONFIG_DIR) + "/classes_rellis3d.yaml";
}

// A fresh directory under the build tree, of this process only (`<name>.<pid>`: ctest -j runs
// every test in its own process, several at once), removed when the process exits.
inline std::string freshDir(const std::string& name) {
  static std::vector<std::filesystem::path> made;
  if (made.empty()) {
    std::atexit([] {
      std::error_code ec;
      for (const auto& p : made) std::filesystem::remove_all(p, ec);
    });
  }
  const std::filesystem::path p =
      std::filesystem::path(EVIDENTIAL_TEST_TMP_DIR) / (name + "." + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  made.push_back(p);
  return p.string();
}

// Runs `child` (it must not return: loop or exec) in a forked process and kills it with SIGKILL
// after `delay_ms`: a writer killed at that moment. Returns false when fork or wait failed.
inline bool killedAfter(double delay_ms, const std::function<void()>& child) {
  const pid_t pid = ::fork();
  if (pid < 0) return false;
  if (pid == 0) {
    child();
    ::_exit(127);
  }
  std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(delay_ms));
  ::kill(pid, SIGKILL);
  return ::waitpid(pid, nullptr, 0) == pid;
}

// The CLI (EVIDENTIAL_TEST_CLI) run with `args`: its exit status and stdout + stderr.
struct CliResult {
  int status = 0;
  std::string output;
};

inline CliResult runCli(const std::string& args) {
  const std::string cmd = std::string(EVIDENTIAL_TEST_CLI) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  CliResult r;
  if (!pipe) return {127, "popen failed: " + cmd};
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  r.status = WEXITSTATUS(pclose(pipe));
  return r;
}

template <typename T>
void writeBinary(const std::string& path, const std::vector<T>& values) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(values.data()),
            std::streamsize(values.size() * sizeof(T)));
}

}  // namespace tools_test
