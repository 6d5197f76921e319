// A static environment: named primitive obstacles with poses, read from a JSON file
// (schemas/environment.schema.json).
#pragma once

#include <string>
#include <vector>

#include "lazyboe/common/json_fields.h"
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
  std::string path;    // the file it was read from; empty for a scene given inline
  std::string origin;  // the file, or where an inline scene stands ("line 3: scene"): for errors
  std::string description;
  std::vector<Obstacle> obstacles;
  // Content identity: a hash of the parsed description (whitespace, key order and number
  // spelling do not count), so the same scene from a file or inline is the same scene.
  std::string identity;
};

// Throws Error naming the file and field for anything missing or malformed.
Environment load_environment(const std::string& path);
// The same for an environment object held in memory (a query's inline scene); `path`: the file
// it came from, or empty.
Environment environment_from_json(const JsonField& root, const std::string& path);

std::string default_environment_path();  // the bundled table.json

}  // namespace lazyboe
