#include "lazyboe/common/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lazyboe {

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof buf, "%ldh%02ldm", s / 3600, (s % 3600) / 60);
  } else if (s >= 60) {
    std::snprintf(buf, sizeof buf, "%ldm%02lds", s / 60, s % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%lds", s);
  }
  return buf;
}

Progress::Progress(std::string label, uint64_t total, bool quiet)
    : label_(std::move(label)),
      total_(total),
      quiet_(quiet),
      tty_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

double Progress::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::update(uint64_t done, const std::string& detail) {
  if (!started_) {
    start_done_ = done;
    started_ = true;
  }
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  const double since = std::chrono::duration<double>(now - last_draw_).count();
  const int decile = total_ ? static_cast<int>(10 * done / total_) : 10;
  const bool due = tty_ ? since >= 0.2 || done >= total_ : decile != last_decile_ || since >= 30;
  if (!due) return;
  last_draw_ = now;
  last_decile_ = decile;
  draw(done, detail);
}

void Progress::draw(uint64_t done, const std::string& detail) {
  const double t = elapsed();
  const double rate = t > 0 ? (done - start_done_) / t : 0;
  const double eta = rate > 0 ? (total_ - std::min(done, total_)) / rate : NAN;
  const double frac = total_ ? std::min(1.0, static_cast<double>(done) / total_) : 1.0;
  char line[256];
  if (tty_) {
    const int width = 24, filled = static_cast<int>(frac * width);
    const std::string bar = std::string(filled, '#') + std::string(width - filled, '.');
    std::snprintf(line, sizeof line, "\r%s [%s] %llu/%llu %5.1f%% %s %.0f/s ETA %s\x1b[K",
                  label_.c_str(), bar.c_str(), static_cast<unsigned long long>(done),
                  static_cast<unsigned long long>(total_), 100 * frac, detail.c_str(), rate,
                  format_duration(eta).c_str());
  } else {
    std::snprintf(line, sizeof line, "%s: %llu/%llu (%.1f%%) %s %.0f/s, elapsed %s, ETA %s\n",
                  label_.c_str(), static_cast<unsigned long long>(done),
                  static_cast<unsigned long long>(total_), 100 * frac, detail.c_str(), rate,
                  format_duration(t).c_str(), format_duration(eta).c_str());
  }
  std::fputs(line, stderr);
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::finish() {
  if (!quiet_ && tty_ && drawn_) std::fputs("\n", stderr);
  drawn_ = false;
}

}  // namespace lazyboe
