// Before/after figures of concurrent writers (docs/experiments/reliability.md). Built against the
// library of a given commit; OLD_WRITERS selects the writers main had before the fix.
//   writer_trials threads DIR      10 rounds of two threads x 10 saveMap of one path, a load after
//   each writer_trials export DIR N     N kill -9 during a ColorOcTree export of a map
//   writer_trials temps DIR N      N kill -9 during saveMap, then one save: temporaries left
#include <dirent.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <thread>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/io.h"

using namespace evidential_octomap;

std::string readFile(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::unique_ptr<EvidentialOcTree> blockMap(int side, unsigned seed) {
  auto tree = std::make_unique<EvidentialOcTree>(0.1, 8);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> v(0.f, 40.f);
  octomap::Pointcloud pts;
  std::vector<float> ev;
  for (int x = 0; x < side; ++x)
    for (int y = 0; y < side; ++y) {
      pts.push_back(2.f + 0.1f * x, 0.1f * y - 1.f, 0.3f * (x % 3));
      for (int c = 0; c < 8; ++c) ev.push_back(v(rng));
    }
  tree->insertSemanticScan(pts, ev, octomap::point3d(0.f, 0.f, 0.f));
  return tree;
}

std::string bytesOf(const EvidentialOcTree& t) {
  std::ostringstream out;
  out.precision(17);
  t.write(out);
  return out.str();
}

size_t countTemps(const std::string& dir) {
  size_t n = 0;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) n += std::string(e->d_name).find("tmp") != std::string::npos;
    closedir(d);
  }
  return n;
}

int main(int argc, char** argv) {
  const std::string mode = argv[1], dir = argv[2];
  if (mode == "threads") {
    const auto a = blockMap(120, 1), b = blockMap(130, 2);
    const std::string path = dir + "/map.ot", sa = bytesOf(*a), sb = bytesOf(*b);
    saveMap(*a, path);
    std::atomic<int> ok{0}, failed{0};
    auto writer = [&](const EvidentialOcTree& t) {
      for (int i = 0; i < 10; ++i) {
        try {
          saveMap(t, path);
          ++ok;
        } catch (...) {
          ++failed;
        }
      }
    };
    int torn = 0, checks = 0;
    for (int round = 0; round < 10; ++round) {
      std::thread t1(writer, std::cref(*a)), t2(writer, std::cref(*b));
      t1.join();
      t2.join();
      ++checks;
      try {
        const std::string got = bytesOf(*loadMap(path));
        if (got != sa && got != sb) ++torn;
      } catch (...) {
        ++torn;
      }
    }
    std::cout << "threads: " << checks << " rounds of 2 threads x 10 saves of one path: " << torn
              << " files torn or unloadable after a round; saves reporting success " << ok
              << ", failing " << failed << "\n";
  } else if (mode == "export") {
    const int n = std::stoi(argv[3]);
    const auto tree = blockMap(400, 3);
    ClassTable classes;
    for (int c = 0; c < 8; ++c) {
      classes.names.push_back("c" + std::to_string(c));
      classes.colors.push_back({uint8_t(30 * c), 100, 200});
    }
    const auto color = toColorOcTree(*tree, classes, ColorMode::kClass);
    const std::string path = dir + "/color.ot";
    auto exportOnce = [&] {
#ifdef OLD_WRITERS
      color->write(path);  // what `export --color-octree` did
#else
      writeFileAtomically(path, [&](std::ostream& out) { return color->write(out) && out.good(); });
#endif
    };
    exportOnce();
    const std::string before = readFile(path);
    const auto t0 = std::chrono::steady_clock::now();
    exportOnce();
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> delay(0.0, 3.0 * ms);
    int destroyed = 0;
    for (int i = 0; i < n; ++i) {
      const pid_t pid = fork();
      if (pid == 0) {
        for (;;) exportOnce();
      }
      std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(delay(rng)));
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
      if (readFile(path) != before) ++destroyed;
    }
    std::cout << "export: " << n << " kill -9 during ColorOcTree exports (" << before.size()
              << " B, " << ms << " ms each): previous file destroyed in " << destroyed << "\n";
  } else if (mode == "temps") {
    const int n = std::stoi(argv[3]);
    const auto tree = blockMap(400, 4);
    const std::string path = dir + "/map.ot";
    saveMap(*tree, path);
    const auto t0 = std::chrono::steady_clock::now();
    saveMap(*tree, path);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> delay(0.0, 2.0 * ms);
    for (int i = 0; i < n; ++i) {
      const pid_t pid = fork();
      if (pid == 0) {
        for (;;) saveMap(*tree, path);
      }
      std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(delay(rng)));
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    const size_t left = countTemps(dir);
    saveMap(*tree, dir + "/other.ot");  // a later save in the same directory
    std::cout << "temps: " << n << " kill -9 during saveMap (" << ms << " ms each): " << left
              << " temporaries left; after one more save in the directory: " << countTemps(dir)
              << "\n";
  }
  return 0;
}
