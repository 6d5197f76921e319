// A payload the arm carries (a grasped object, a tool): a rigid body fixed to one link, given
// per query. The bundle's edges are commands and stay valid as such; what changes is the
// dynamics they are simulated with, so a payload makes a new RobotModel (the bundle's robot
// with the payload merged into the link's moving body) for the query's world.
#pragma once

#include <string>

#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

class JsonField;

struct Payload {
  int link = -1;    // the link it is fixed to (index into RobotModel::links); -1: no payload
  double mass = 0;  // kg
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      // centre of mass, link frame, m
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // about the centre of mass, kg m^2
  Eigen::Vector3d box = Eigen::Vector3d::Zero();      // its extents when given as a box
  bool any() const { return link >= 0; }
};

// The inertia about its centre of a solid box of `mass` with full extents `size`.
Eigen::Matrix3d box_inertia(double mass, const Eigen::Vector3d& size);

// Reads {"mass": kg, "com": [x, y, z], "inertia": [ixx, ixy, ixz, iyy, iyz, izz] (URDF's
// order; default: a point mass) or "box": [sx, sy, sz] (a solid box; with it "density", kg/m^3,
// may replace "mass"), "link": name (default: the tip link)}. Throws Error naming the field for
// a negative mass, an inertia that is not positive semi-definite, an unknown link or the base.
Payload payload_from_json(const JsonField& field, const RobotModel& robot);

// `robot` carrying `payload` (merged into the moving body of its link).
RobotModel with_payload(const RobotModel& robot, const Payload& payload);

// A canonical text of the payload (part of a world's identity); empty without one.
std::string payload_identity(const Payload& payload);

}  // namespace lazyboe
