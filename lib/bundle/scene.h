// The robot and environment of a bundle, and the content identities its header records.
#pragma once

#include <string>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

// Content identity of the inputs, as recorded in a bundle header.
std::string robot_identity(const RobotModel& robot);  // hash of config, URDF and mesh bytes
std::string environment_identity(const Environment& env);

// The robot and environment a bundle was built with: the files given, or those recorded in the
// header when a path is empty, refused (naming the file) unless their content hashes to the
// recorded values. Other tools never assume them.
struct BundleScene {
  RobotModel robot;
  Environment env;
};
BundleScene load_bundle_scene(const BundleHeader& header, std::string robot_path,
                              std::string env_path);
// Its two halves: the robot (planning in another scene still needs the bundle's robot) and the
// environment it was built in.
RobotModel load_bundle_robot(const BundleHeader& header, std::string robot_path);
Environment load_bundle_environment(const BundleHeader& header, std::string env_path);

}  // namespace lazyboe
