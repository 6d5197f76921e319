// The shared shell of every command-line tool: library errors become one line on stderr and
// exit status 1; command-line mistakes are reported by CLI11 (exit status 2 or more).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "common/error.h"

namespace lazyboe {

// Command-line mistakes in one line too: "<tool>: error: <what> (see --help)".
inline void one_line_cli_errors(CLI::App& app, const std::string& tool) {
  app.failure_message([tool](const CLI::App*, const CLI::Error& e) {
    return tool + ": error: " + e.what() + " (see --help)\n";
  });
}

template <typename Body>
int run_tool(const char* tool, Body&& body) {
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
