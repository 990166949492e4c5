#include "progress_bar.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

namespace evidential_octomap::tools {

ProgressBar::ProgressBar(size_t total, std::string label, std::string unit, int enabled)
    : ProgressBar(total, std::move(label), std::move(unit), std::cerr,
                  enabled < 0 ? isatty(fileno(stderr)) != 0 : enabled != 0) {}

ProgressBar::ProgressBar(size_t total, std::string label, std::string unit, std::ostream& out,
                         bool enabled)
    : total_(total),
      label_(std::move(label)),
      unit_(std::move(unit)),
      out_(&out),
      enabled_(enabled),
      start_(std::chrono::steady_clock::now()) {
  if (enabled_) draw();
}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::tick(size_t n) {
  done_ += n;
  if (enabled_) draw();
}

void ProgressBar::finish() {
  if (finished_) return;
  finished_ = true;
  if (enabled_) {
    draw();
    *out_ << '\n' << std::flush;
  }
}

void ProgressBar::draw() {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  *out_ << '\r' << format(label_, done_, total_, elapsed, unit_) << "\033[K" << std::flush;
}

std::string ProgressBar::formatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const long s = std::lround(seconds);
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  }
  return buf;
}

std::string ProgressBar::format(const std::string& label, size_t done, size_t total,
                                double elapsed_s, const std::string& unit, int width) {
  done = std::min(done, total);
  const double frac = total > 0 ? double(done) / double(total) : 1.0;
  const int filled = int(std::floor(frac * width + 1e-9));
  std::ostringstream s;
  if (!label.empty()) s << label << ' ';
  s << '[' << std::string(filled, '#') << std::string(width - filled, '-') << "] " << done << '/'
    << total << "  " << int(std::floor(frac * 100.0 + 1e-9)) << "%  ";
  if (done > 0 && elapsed_s > 0) {
    const double rate = double(done) / elapsed_s;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", rate);
    s << buf << ' ' << unit << "/s  ETA " << formatDuration(double(total - done) / rate);
  } else {
    s << "-- " << unit << "/s  ETA --:--";
  }
  return s.str();
}

}  // namespace evidential_octomap::tools
