// The bundled Panda on the table, with a simulator and its workspace: what the parsers that
// check states (query lines, bench problems) are given, as the tools give them theirs.
#pragma once

#include "fuzz_util.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe::fuzz {

struct TableScene {
  RobotModel robot = load_robot(source_path("data/robots/panda.json"));
  Environment env = load_environment(source_path("data/environments/table.json"));
  CollisionModel collision = build_collision_model(robot, env);
  Simulator sim{robot, collision, SimulationOptions{}};
  SimulatorWorkspace ws{sim};
};

// Built on first use, once per process.
inline TableScene& table_scene() {
  static TableScene scene;
  return scene;
}

}  // namespace lazyboe::fuzz
