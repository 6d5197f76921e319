// A task's limits on one link's motion (issue 29), which the simulator checks at every tick
// and the trajectory checker at every sample.
#pragma once

#include <limits>

#include "lazyboe/robot/kinematics.h"

namespace lazyboe {

class JsonField;

// Limits on one link's motion for a task (issue 29; the "waiter" carrying an open cup): the
// linear speed of its origin at every control tick (the Jacobian times dq), its linear
// acceleration as the change of that velocity over a tick (a finite difference at the control
// rate, as a 1 kHz trajectory check sees it), and the tilt of one of its axes from the
// vertical (against gravity). A rollout starts and ends at rest, so a junction of two rollouts
// sees the velocity change of the first one's last tick and the second one's first: each gets
// half the acceleration limit there (as with the torque rate).
struct EndEffectorLimits {
  int link = -1;  // the limited link; -1: no limits
  double max_linear_speed = std::numeric_limits<double>::infinity();         // m/s
  double max_linear_acceleration = std::numeric_limits<double>::infinity();  // m/s^2
  double max_tilt = std::numeric_limits<double>::infinity();                 // rad
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit, link frame: kept near vertical
  bool any() const { return link >= 0; }
};

// Tilt of the limited link's axis from the vertical at the last forward_kinematics, rad.
double end_effector_tilt(const RobotModel& robot, const RobotData& data,
                         const EndEffectorLimits& limits);

// Reads {"max_linear_speed": m/s, "max_linear_acceleration": m/s^2, "max_tilt": rad, "axis":
// [x, y, z] (link frame; default: the link's axis that is vertical at `start`, so that a
// container is carried as it is held), "link": name (default: the tip link)}. Throws Error
// naming the field for a value out of range, a zero axis or an unknown link.
EndEffectorLimits end_effector_limits_from_json(const JsonField& field, const RobotModel& robot,
                                                const JointVectorRef& start, RobotData& data);

}  // namespace lazyboe
