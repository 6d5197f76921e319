// One lazyboe-query line (JSON, schemas/query.schema.json): parse_query with the bundled Panda
// on the table, then the error result the tool writes for a refused line.
#include "fuzz_util.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/io/query_io.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/simulator.h"

using namespace lazyboe;

namespace {
struct TableScene {
  RobotModel robot = load_robot(fuzz::source_path("data/robots/panda.json"));
  Environment env = load_environment(fuzz::source_path("data/environments/table.json"));
  CollisionModel collision = build_collision_model(robot, env);
  Simulator sim{robot, collision, SimulationOptions{}};
  SimulatorWorkspace ws{sim};
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static TableScene scene;
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::string id;
  try {
    const Query q = parse_query(text, 1, scene.robot, scene.sim, scene.ws, QueryDefaults{}, id);
    (void)q;
  } catch (const Error& e) {
    // lazyboe-query answers a refused line with this result line; it must serialize.
    (void)error_json(id, 1, "", e.what()).dump();
  }
  return 0;
}
