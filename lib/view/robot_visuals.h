// The robot's visual geometry, for the viewer only: the URDF's <visual> elements (meshes through
// Assimp, as the collision meshes; spheres, boxes, cylinders), read from the robot's URDF when a
// page is written. Planning never reads them (they are not part of the robot's identity); a
// visual that cannot be read leaves its link drawn from its collision geometry, with a warning.
#pragma once

#include <string>
#include <vector>

#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

struct RobotVisual {
  int link = 0;  // index into RobotModel::links
  std::string name;
  Shape shape;   // a mesh: its triangles about the shape's frame (scaled)
  Pose in_link;  // shape frame in the link frame
};

// Every visual of the model's links, in link order; `warnings` gets one line per link whose
// visuals could not all be read (none of that link's visuals is returned then).
std::vector<RobotVisual> load_robot_visuals(const RobotModel& robot,
                                            std::vector<std::string>& warnings);

}  // namespace lazyboe
