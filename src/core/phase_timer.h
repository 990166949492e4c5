// Wall and process CPU time of one phase of an insert (InsertStats' ms_* and cpu_ms_*).
#pragma once

#include <time.h>

#include <chrono>

namespace evidential_octomap {

struct PhaseTimer {
  using Clock = std::chrono::steady_clock;

  static double processCpuMs() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
  }

  Clock::time_point wall = Clock::now();
  double cpu = processCpuMs();

  void stop(double* wall_ms, double* cpu_ms) const {
    *wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - wall).count();
    *cpu_ms = processCpuMs() - cpu;
  }
};

}  // namespace evidential_octomap
