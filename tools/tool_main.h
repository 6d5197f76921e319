// The shared shell of every command-line tool: library errors become one line on stderr and
// exit status 1; command-line mistakes are reported by CLI11 (exit status 2 or more).
#pragma once

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <string>

#include "lazyboe/common/error.h"
#include "lazyboe/common/numbers.h"

namespace lazyboe {

// Command-line mistakes in one line too: "<tool>: error: <what> (see --help)".
inline void one_line_cli_errors(CLI::App& app, const std::string& tool) {
  app.failure_message([tool](const CLI::App*, const CLI::Error& e) {
    return tool + ": error: " + e.what() + " (see --help)\n";
  });
}

// Option validators with plain messages ("must be a whole number > 0").
inline CLI::Validator whole_number(bool allow_zero) {
  return CLI::Validator(
      [allow_zero](std::string& text) -> std::string {
        const bool digits =
            !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
        if (!digits || text.size() > 19)
          return allow_zero ? "must be a whole number >= 0" : "must be a whole number > 0";
        if (!allow_zero && std::stoull(text) == 0) return "must be a whole number > 0";
        return "";
      },
      allow_zero ? "INT>=0" : "INT>0");
}

// A real option parsed strictly (plain decimal, finite: "nan", "inf", "0x10" are refused) and
// within `range`: "--budget: 'nan' is not a number (accepted: finite decimal numbers in (0,
// 1000000] s)".
inline CLI::Validator real_in(const RealRange& range, const std::string& unit = "") {
  return CLI::Validator(
      [range, unit](std::string& text) -> std::string {
        double v = 0;
        if (!parse_decimal(text, v))
          return "'" + text + "' is not a number (accepted: finite decimal numbers in " +
                 range.text() + unit + ")";
        if (!range.contains(v))
          return number_text(v) + " is outside the accepted range " + range.text() + unit;
        return "";
      },
      "NUM in " + range.text());
}

inline CLI::Validator number_at_least_zero() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!parse_decimal(text, v) || !(v >= 0) || v > 1e300) return "must be a number >= 0";
        return "";
      },
      "NUM>=0");
}

// SIGINT/SIGTERM handling for long jobs, and SIGUSR1 for jobs under mpirun or Slurm (mpirun
// kills the ranks on Ctrl-C but forwards SIGUSR1 to them; `sbatch --signal` sends it before a
// time limit). The first signal asks for a checkpoint and a clean stop (stop_requested() turns
// true). A second one more than a second later (a user pressing Ctrl-C again) ends the process
// at once; the last checkpoint on disk stays valid. Duplicates within a second (a signal sent
// to the whole process group, as `timeout` does) are ignored.
namespace detail {
inline std::atomic<bool> g_stop{false};
inline std::atomic<long> g_first_signal_ms{0};
inline long monotonic_ms() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);  // async-signal-safe
  return ts.tv_sec * 1000L + ts.tv_nsec / 1000000L;
}
inline void on_stop_signal(int) {
  const long now = monotonic_ms();
  if (!g_stop.exchange(true)) {
    g_first_signal_ms = now;
  } else if (now - g_first_signal_ms > 1000) {
    _exit(130);
  }
}
}  // namespace detail

inline void install_stop_handlers() {
  std::signal(SIGINT, detail::on_stop_signal);
  std::signal(SIGTERM, detail::on_stop_signal);
  std::signal(SIGUSR1, detail::on_stop_signal);
}
inline bool stop_requested() { return detail::g_stop.load(); }

template <typename Body>
int run_tool(const char* tool, Body&& body) {
  // Past a file-size limit (ulimit -f) a write fails with EFBIG and is reported like a full
  // disk, instead of the signal ending the process.
  std::signal(SIGXFSZ, SIG_IGN);
  try {
    return body();
  } catch (const CLI::ParseError&) {
    throw;
  } catch (const Error& e) {
    std::fprintf(stderr, "%s: error: %s\n", tool, e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", tool, e.what());
  }
  return 1;
}

}  // namespace lazyboe
