// The robot config (JSON, schemas/robot.schema.json) as load_robot reads it, next to the
// bundled Panda URDF it names, then used as the tools use a robot.
#include "fuzz_util.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"

using namespace lazyboe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string urdf = fuzz::write_scratch(
      "panda.urdf", fuzz::read_text(fuzz::source_path("data/robots/panda.urdf")));
  const std::string path = fuzz::write_scratch("robot.json", data, size);
  try {
    const RobotModel robot = load_robot(path);
    fuzz::use_robot(robot, Environment{});
  } catch (const Error&) {
    // A refusal with a message is the expected outcome of most inputs; anything else
    // (another exception, a crash, a sanitizer report) is a finding.
  }
  return 0;
}
