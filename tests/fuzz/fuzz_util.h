// Shared by the fuzz targets: the parsers under test read files, so each input is written to a
// scratch file (in /dev/shm when there is one: no disk I/O per execution) and the library's own
// entry point reads it, exactly as the tools do.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace lazyboe::fuzz {

// A directory of this process, removed at exit.
const std::string& scratch_dir();
// Writes `size` bytes to scratch_dir()/name and returns its path.
std::string write_scratch(const std::string& name, const uint8_t* data, size_t size);
std::string write_scratch(const std::string& name, const std::string& text);
// A file of the repository (data/..., tests/...).
std::string source_path(const std::string& relative);
std::string read_text(const std::string& path);

}  // namespace lazyboe::fuzz

// The libFuzzer entry point every target defines.
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace lazyboe {
struct RobotModel;
struct Environment;
namespace fuzz {
// What every tool does with a robot it has loaded: the collision model in `env`, the
// simulator, and the limits, dynamics and collision of one state at rest (the middle of the
// sampling region), so that values the loader accepts are also used.
void use_robot(const RobotModel& robot, const Environment& env);
}  // namespace fuzz
}  // namespace lazyboe
