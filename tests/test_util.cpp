#include "test_util.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace lazyboe::test {

namespace fs = std::filesystem;

std::string source_path(const std::string& relative) {
  return std::string(LAZYBOE_SOURCE_DIR) + "/" + relative;
}

std::string tool_path(const std::string& tool) {
  return std::string(LAZYBOE_TOOLS_DIR) + "/" + tool;
}

const RobotModel& panda() {
  static const RobotModel model = load_robot(source_path("data/robots/panda.json"));
  return model;
}

Scene::Scene(const std::string& env_name, SimulationOptions options)
    : robot(panda()),
      env(load_environment(source_path("data/environments/" + env_name + ".json"))),
      collision(build_collision_model(robot, env)),
      sim(robot, collision, options) {}

namespace {
struct TempDir {
  std::string path;
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "lazyboe-test-XXXXXX").string();
    path = ::mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
}  // namespace

std::string temp_dir() {
  static TempDir dir;
  return dir.path;
}

std::string write_temp_file(const std::string& name, const std::string& content) {
  const std::string path = temp_dir() + "/" + name;
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path) << content;
  return path;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CommandResult run(const std::string& command) {
  const std::string out = temp_dir() + "/cmd.out", err = temp_dir() + "/cmd.err";
  const int status = std::system((command + " >" + out + " 2>" + err).c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}

double time_scale() {
  const char* s = std::getenv("LAZYBOE_TEST_TIME_SCALE");
  const double v = s ? std::atof(s) : 1.0;
  return v > 0 ? v : 1.0;
}

std::string watchdog(double seconds) {
  return "timeout -s KILL " + std::to_string(seconds * time_scale()) + " ";
}

}  // namespace lazyboe::test
