// Progress on stderr for long jobs: a redrawn bar on a terminal, plain lines (every 10% or 30 s)
// otherwise, nothing with quiet.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace lazyboe {

class Progress {
 public:
  Progress(std::string label, uint64_t total, bool quiet);
  // `done` of `total` units; `detail` is appended (for example "valid 96.1%").
  void update(uint64_t done, const std::string& detail = "");
  void finish();  // ends the bar's line
  double elapsed() const;

 private:
  void draw(uint64_t done, const std::string& detail);
  std::string label_;
  uint64_t total_;
  uint64_t start_done_ = 0;  // units already done when this run started (resume)
  bool started_ = false;
  bool quiet_, tty_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  int last_decile_ = -1;
  bool drawn_ = false;
};

std::string format_duration(double seconds);  // "1h02m", "3m12s", "42s"

}  // namespace lazyboe
