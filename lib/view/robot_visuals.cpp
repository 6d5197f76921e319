#include "lazyboe/view/robot_visuals.h"

#include <memory>

#include "lazyboe/collision/link_geometry.h"
#include "lazyboe/collision/mesh.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/resource_path.h"
#include "lazyboe/robot/urdf_parser.h"
#include "lazyboe/robot/urdf_pose.h"

namespace lazyboe {
namespace {

// The visuals of one URDF link; throws Error naming the element for one that cannot be read.
std::vector<RobotVisual> link_visuals(const RobotModel& robot, const urdf::Link& link, int index,
                                      const std::vector<std::string>& search) {
  std::vector<RobotVisual> visuals;
  for (size_t k = 0; k < link.visual_array.size(); ++k) {
    const urdf::Visual& v = *link.visual_array[k];
    if (!v.geometry) continue;
    const std::string where =
        robot.files.urdf + ": link '" + link.name + "' visual " + std::to_string(k);
    RobotVisual visual;
    visual.link = index;
    visual.name = link.name + (link.visual_array.size() > 1 ? "/" + std::to_string(k) : "");
    visual.in_link = pose_from_urdf(v.origin);
    if (v.geometry->type == urdf::Geometry::MESH) {
      const auto& m = static_cast<const urdf::Mesh&>(*v.geometry);
      const std::string file = resolve_urdf_resource(m.filename, robot.files.urdf, search, where);
      try {
        visual.shape.type = ShapeType::Mesh;
        visual.shape.mesh = std::make_shared<const TriangleMesh>(
            load_mesh(file, Eigen::Vector3d(m.scale.x, m.scale.y, m.scale.z)));
      } catch (const Error& e) {
        fail(where, e.what());
      }
    } else {
      visual.shape = urdf_primitive_shape(*v.geometry, where);
    }
    visuals.push_back(std::move(visual));
  }
  return visuals;
}

}  // namespace

std::vector<RobotVisual> load_robot_visuals(const RobotModel& robot,
                                            std::vector<std::string>& warnings) {
  std::vector<RobotVisual> visuals;
  urdf::ModelInterfaceSharedPtr urdf_model;
  try {
    urdf_model = parse_urdf_file(robot.files.urdf);
  } catch (const Error& e) {
    warnings.push_back(std::string(e.what()) + ": the robot is drawn from its collision geometry");
    return visuals;
  }
  const std::vector<std::string> search = package_search_path(robot.files.package_path);
  for (size_t i = 0; i < robot.links.size(); ++i) {
    const urdf::LinkConstSharedPtr link = urdf_model->getLink(robot.links[i].name);
    if (!link) continue;
    try {
      for (RobotVisual& v : link_visuals(robot, *link, static_cast<int>(i), search))
        visuals.push_back(std::move(v));
    } catch (const Error& e) {
      warnings.push_back(std::string(e.what()) + ": the link is drawn from its collision geometry");
    }
  }
  return visuals;
}

}  // namespace lazyboe
