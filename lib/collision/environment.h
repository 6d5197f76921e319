// A static environment: named primitive obstacles with poses, read from a JSON file
// (schemas/environment.schema.json).
#pragma once

#include <string>
#include <vector>

#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

struct Obstacle {
  std::string name;
  Shape shape;
  Pose pose;                               // in the robot's base frame
  std::vector<std::string> allowed_links;  // robot links allowed to touch this obstacle
};

struct Environment {
  std::string name;
  std::string path;
  std::string description;
  std::vector<Obstacle> obstacles;
};

// Throws Error naming the file and field for anything missing or malformed.
Environment load_environment(const std::string& path);

std::string default_environment_path();  // the bundled table.json

}  // namespace lazyboe
