// The URDF (check_urdf_values, then urdfdom, then the model's own checks) as load_robot reads
// it through the bundled Panda config, then used as the tools use a robot.
#include "fuzz_util.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"

using namespace lazyboe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string config = fuzz::write_scratch(
      "robot.json", fuzz::read_text(fuzz::source_path("data/robots/panda.json")));
  fuzz::write_scratch("panda.urdf", data, size);  // the file the config names
  try {
    const RobotModel robot = load_robot(config);
    fuzz::use_robot(robot, Environment{});
  } catch (const Error&) {
    // Refused with a message: expected. Anything else is a finding.
  }
  return 0;
}
