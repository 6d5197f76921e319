#include "fuzz_util.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/simulator.h"

namespace fs = std::filesystem;

namespace lazyboe::fuzz {
namespace {
struct ScratchDir {
  std::string path;
  ScratchDir() {
    const fs::path base =
        fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    std::string pattern = (base / "lazyboe-fuzz-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) {
      std::perror("lazyboe fuzz: mkdtemp");
      std::abort();
    }
    path = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
}  // namespace

const std::string& scratch_dir() {
  static const ScratchDir dir;
  return dir.path;
}

std::string write_scratch(const std::string& name, const uint8_t* data, size_t size) {
  const std::string path = scratch_dir() + "/" + name;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  // An empty input may come with a null `data`, which fwrite must not get.
  if (!f || (size > 0 && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
    std::perror(("lazyboe fuzz: " + path).c_str());
    std::abort();  // the harness, not the parser: stop rather than fuzz a stale file
  }
  return path;
}

std::string write_scratch(const std::string& name, const std::string& text) {
  return write_scratch(name, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

std::string source_path(const std::string& relative) {
  return std::string(LAZYBOE_SOURCE_DIR) + "/" + relative;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "lazyboe fuzz: cannot read %s\n", path.c_str());
    std::abort();
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void use_robot(const RobotModel& robot, const Environment& env) {
  const CollisionModel collision = build_collision_model(robot, env);
  const Simulator sim(robot, collision, SimulationOptions{});
  SimulatorWorkspace ws(sim);
  const Eigen::VectorXd q = 0.5 * (robot.region.lower + robot.region.upper);
  check_state(sim, ws, q);
  gravity_torques(robot, ws.robot, q);
  mass_matrix(robot, ws.robot, q);
  collision_lever_arms(robot, collision);
}

}  // namespace lazyboe::fuzz
