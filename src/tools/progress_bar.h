// A progress bar with rate and ETA on stderr; silent when stderr is not a terminal, so logs and
// CI output stay clean. format() is pure and unit-tested.
#pragma once

#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <string>

namespace evidential_octomap::tools {

class ProgressBar {
 public:
  // enabled: 1 on, 0 off, -1 (default) on exactly when stderr is a TTY.
  ProgressBar(size_t total, std::string label, std::string unit = "scan", int enabled = -1);
  ProgressBar(size_t total, std::string label, std::string unit, std::ostream& out, bool enabled);
  ~ProgressBar();

  void tick(size_t n = 1);  // n more items done; redraws
  void finish();            // final line and newline (once)
  bool enabled() const { return enabled_; }

  // "label [#########-----------] 3/10  30%  1.50 scan/s  ETA 0:05". Rate and ETA read "--"
  // until something is done; done > total is clamped.
  static std::string format(const std::string& label, size_t done, size_t total,
                            double elapsed_s, const std::string& unit = "scan", int width = 24);
  // "0:05", "12:34", "1:02:03"; negative or non-finite -> "--:--".
  static std::string formatDuration(double seconds);

 private:
  void draw();

  size_t total_, done_ = 0;
  std::string label_, unit_;
  std::ostream* out_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace evidential_octomap::tools
