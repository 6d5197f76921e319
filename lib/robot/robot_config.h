// The robot config reader: a robot config file (JSON, schemas/robot-config.schema.json) and the
// URDF it points at, into a RobotModel. The URDF side is urdf_parser.cpp; the model itself,
// read-only once made, is robot_model.h.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "lazyboe/common/data_dir.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

class JsonField;

// Loads a robot config (JSON; or a bundled robot by name: "panda", "ur5") and the URDF it
// points at. Throws Error naming the file and field for anything missing, malformed or not
// physical.
RobotModel load_robot(const std::string& config_path);
// The same for a config held in memory; `config_path` names it in errors and is where its
// relative paths (urdf, package_path) start.
RobotModel robot_from_json(const nlohmann::json& config, const std::string& config_path);

// The moving joints (limits as the URDF gives them) of the chain from `base_link` to
// `tip_link` (empty: the defaults of the config's fields), for writing a config.
std::vector<Joint> chain_joints(const std::string& urdf_path, const std::string& base_link,
                                const std::string& tip_link);

// The link an object's "link" member names (default: the tip link); throws Error naming the
// field for an unknown one (unknown_link's text).
int link_field(const JsonField& object, const RobotModel& robot);

// The bundled Panda's config (data_dir()/robots/panda.json).
std::string default_robot_path();

}  // namespace lazyboe
