// The environment file (JSON, schemas/environment.schema.json) as load_environment reads it,
// then the collision model of the bundled Panda in it and one collision check, as every tool
// does with an environment.
#include "fuzz_util.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"

using namespace lazyboe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const RobotModel robot = load_robot(fuzz::source_path("data/robots/panda.json"));
  const std::string path = fuzz::write_scratch("environment.json", data, size);
  try {
    const Environment env = load_environment(path);
    fuzz::use_robot(robot, env);
  } catch (const Error&) {
    // Refused with a message: expected. Anything else is a finding.
  }
  return 0;
}
