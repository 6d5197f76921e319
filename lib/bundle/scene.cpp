#include "lazyboe/bundle/scene.h"

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"
#include "lazyboe/robot/robot_config.h"

namespace lazyboe {

std::string robot_identity(const RobotModel& robot) {
  std::vector<std::string> files = {robot.files.config, robot.files.urdf};
  files.insert(files.end(), robot.files.resources.begin(), robot.files.resources.end());
  return hash_files(files);
}

std::string environment_identity(const Environment& env) {
  std::vector<std::string> files = {env.path};  // and what its objects read (meshes, clouds)
  files.insert(files.end(), env.files.begin(), env.files.end());
  return hash_files(files);
}

namespace {

// A file named in the bundle that is no longer there: say where the path came from and how to
// give it instead.
void require_recorded_file(const std::string& path, const char* what, const char* option) {
  if (std::filesystem::exists(path)) return;
  fail(path, std::string("cannot open the ") + what + " recorded in the bundle (" +
                 std::strerror(ENOENT) + "; relative paths are taken from the current directory" +
                 "): moved? give it with " + option + " FILE");
}

}  // namespace

RobotModel load_bundle_robot(const BundleHeader& h, std::string robot_path) {
  if (robot_path.empty()) {
    robot_path = h.robot_config;
    require_recorded_file(robot_path, "robot config", "--robot");
  }
  RobotModel robot = load_robot(robot_path);
  const std::string robot_hash = robot_identity(robot);
  if (robot_hash != h.robot_hash) {
    fail(robot_path, "is not the robot the bundle was built with (" + h.robot_config + ", hash " +
                         h.robot_hash + "; this one hashes to " + robot_hash + ")");
  }
  return robot;
}

Environment load_bundle_environment(const BundleHeader& h, std::string env_path) {
  if (env_path.empty()) {
    env_path = h.env_file;
    require_recorded_file(env_path, "environment", "--env");
  }
  Environment env = load_environment(env_path);
  const std::string env_hash = environment_identity(env);
  if (env_hash != h.env_hash) {
    fail(env_path, "is not the environment the bundle was built with (" + h.env_file + ", hash " +
                       h.env_hash + "; this one hashes to " + env_hash + ")");
  }
  return env;
}

BundleScene load_bundle_scene(const BundleHeader& h, std::string robot_path, std::string env_path) {
  return BundleScene{load_bundle_robot(h, std::move(robot_path)),
                     load_bundle_environment(h, std::move(env_path))};
}

}  // namespace lazyboe
