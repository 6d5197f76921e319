// Helpers shared by the tests: bundled files, temporary files, running the tools.
#pragma once

#include <string>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe::test {

std::string source_path(const std::string& relative);  // inside the repository
std::string tool_path(const std::string& tool);        // build/bin/<tool>

const RobotModel& panda();  // loaded once per test binary
// What load_robot(config_path) throws, or "" when it loads.
std::string robot_load_error(const std::string& config_path);

// The bundled Panda in one of the bundled environments, with a simulator over them.
struct Scene {
  explicit Scene(const std::string& env_name, SimulationOptions options = {});
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
  RobotModel robot;
  Environment env;
  CollisionModel collision;
  Simulator sim;
};

// A complete bundle of n edges with random contents in [-3, 3] (not simulated), ragged knots
// (0..5 per edge) and samples (1..12): for the file and index formats.
Bundle random_bundle(size_t n, int dof, uint64_t seed);
// One a BundleView accepts: at least two knots per edge, a finished perturbation analysis.
Bundle viewable_bundle(size_t n, int dof, uint64_t seed);

// A fresh directory under the system temp dir, removed at exit.
std::string temp_dir();
// LAZYBOE_TEST_TIME_SCALE (default 1), for wall-clock budgets and watchdogs: make test-sanitize
// sets it, as the sanitizers slow everything several times over.
double time_scale();
// "timeout -s KILL <seconds * time_scale()> ", to prefix a tool's shell command: a run that does
// not end is killed and fails its test instead of hanging the suite.
std::string watchdog(double seconds);
std::string write_temp_file(const std::string& name, const std::string& content);
std::string read_file(const std::string& path);

struct CommandResult {
  int exit_code = -1;
  std::string out, err;
};
// Runs a shell command, capturing stdout and stderr.
CommandResult run(const std::string& command);

}  // namespace lazyboe::test
