#include "lazyboe/sim/end_effector.h"

#include <algorithm>
#include <cmath>

#include "lazyboe/common/json_fields.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/robot/robot_config.h"

namespace lazyboe {

double end_effector_tilt(const RobotModel& robot, const RobotData& data,
                         const EndEffectorLimits& limits) {
  const Eigen::Vector3d up = -robot.gravity.normalized();
  const double c = (link_pose(robot, data, limits.link).R * limits.axis).dot(up);
  return std::acos(std::clamp(c, -1.0, 1.0));
}

EndEffectorLimits end_effector_limits_from_json(const JsonField& f, const RobotModel& robot,
                                                const JointVectorRef& start, RobotData& data) {
  if (!f.value().is_object()) f.fail("expected an object");
  f.allow_only({"max_linear_speed", "max_linear_acceleration", "max_tilt", "axis", "link"});
  EndEffectorLimits e;
  e.link = link_field(f, robot);
  if (f.has("max_linear_speed"))
    e.max_linear_speed = f.at("max_linear_speed").number_in({0, 1e3, true}, " m/s");
  if (f.has("max_linear_acceleration"))
    e.max_linear_acceleration = f.at("max_linear_acceleration").number_in({0, 1e4, true}, " m/s^2");
  if (f.has("max_tilt")) e.max_tilt = f.at("max_tilt").number_in({0, M_PI}, " rad");
  if (f.has("axis")) {
    const Eigen::Vector3d a = f.at("axis").vec3_in({-1e3, 1e3});
    if (!(a.norm() > 1e-9)) f.at("axis").fail("must not be zero");
    e.axis = a.normalized();
  } else {
    forward_kinematics(robot, data, start);
    e.axis = link_pose(robot, data, e.link).R.transpose() * (-robot.gravity.normalized());
  }
  return e;
}

}  // namespace lazyboe
