// The URDF side of loading a robot (internal; not installed: it names urdfdom's types): the
// file parsed and checked, the chain between two links found, and the model's joints, bodies
// and links built from it. The robot config reader (robot_config.cpp) drives it.
#pragma once

#include <urdf_parser/urdf_parser.h>

#include <string>
#include <vector>

#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

class JsonField;

// Parses a URDF file; one Error naming the file (and line:column for malformed XML), the link
// or the joint for anything missing, malformed or not physical.
urdf::ModelInterfaceSharedPtr parse_urdf_file(const std::string& path);

// The chain from the config's base_link (default: the URDF root) to its tip_link (default:
// follow the only child until the tree ends); `base_name` receives the base link's name.
std::vector<urdf::LinkConstSharedPtr> find_chain(const JsonField& root,
                                                 const urdf::ModelInterface& urdf_model,
                                                 const std::string& upath,
                                                 const std::string& config_path,
                                                 std::string& base_name);

// Walks the chain into `model`: a moving joint starts a new body; fixed joints merge into the
// current one, and links hanging off the chain through fixed joints join their body. Returns
// the URDF link of every model link.
std::vector<urdf::LinkConstSharedPtr> build_bodies(
    RobotModel& model, const std::vector<urdf::LinkConstSharedPtr>& chain,
    const std::string& upath);

}  // namespace lazyboe
