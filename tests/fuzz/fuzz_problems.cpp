// A lazyboe-bench problems file (problems.jsonl, read by --problems-file and by --resume):
// read_problems with the bundled Panda on the table, then written back as a new study does.
#include "fuzz_util.h"
#include "lazyboe/bench/problems.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
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
  const std::string path = fuzz::write_scratch("problems.jsonl", data, size);
  try {
    const std::vector<BenchProblem> problems =
        read_problems(path, scene.sim, scene.ws, QueryDefaults{});
    write_problems(fuzz::scratch_dir() + "/problems-out.jsonl", scene.robot, problems);
  } catch (const Error&) {
    // Refused with a message: expected. Anything else is a finding.
  }
  return 0;
}
