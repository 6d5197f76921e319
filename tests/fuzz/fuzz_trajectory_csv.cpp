// A trajectory CSV (lazyboe-robot validate-trajectory --in): read_trajectory_csv for the
// bundled Panda, then what the tool runs on it: the spacing check and the trajectory checker.
#include "fuzz_util.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/io/trajectory_csv.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/trajectory_check.h"

using namespace lazyboe;

namespace {
struct Checker {
  RobotModel robot = load_robot(fuzz::source_path("data/robots/panda.json"));
  Environment env = load_environment(fuzz::source_path("data/environments/table.json"));
  CollisionModel collision = build_collision_model(robot, env);
  TrajectoryChecker checker{robot, collision};
  TrajectoryCheckWorkspace ws{checker};
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Checker c;
  const std::string path = fuzz::write_scratch("trajectory.csv", data, size);
  try {
    const TrajectoryCsv traj = read_trajectory_csv(path, c.robot.dof);
    if (traj.t.size() < 2 || first_bad_spacing(c.checker, traj.view()) >= 0) return 0;
    const TrajectoryCheckResult r = check_trajectory(c.checker, c.ws, traj.view());
    if (!r.valid) (void)describe_violation(c.checker, r.violation);
  } catch (const Error&) {
    // Refused with a message: expected. Anything else is a finding.
  }
  return 0;
}
