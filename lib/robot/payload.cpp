#include "lazyboe/robot/payload.h"

#include <Eigen/Eigenvalues>
#include <cstdio>

#include "lazyboe/common/error.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/robot/robot_config.h"

namespace lazyboe {

Eigen::Matrix3d box_inertia(double mass, const Eigen::Vector3d& s) {
  const Eigen::Vector3d sq = s.cwiseProduct(s);
  return (mass / 12.0) * Eigen::Vector3d(sq.y() + sq.z(), sq.x() + sq.z(), sq.x() + sq.y())
                             .asDiagonal()
                             .toDenseMatrix();
}

namespace {

Eigen::Matrix3d inertia_from_json(const JsonField& f) {
  const std::vector<double> v = f.numbers();
  if (v.size() != 6) f.fail("expected 6 numbers [ixx, ixy, ixz, iyy, iyz, izz] (kg m^2)");
  Eigen::Matrix3d I;
  I << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
  // Eigenvalues of a symmetric matrix; a rounding-sized negative one is still semi-definite.
  const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I).eigenvalues();
  if (ev.minCoeff() < -1e-12 * std::max(1.0, ev.cwiseAbs().maxCoeff())) {
    char what[160];
    std::snprintf(what, sizeof what,
                  "not positive semi-definite (eigenvalues %.6g, %.6g, %.6g kg m^2)", ev[0], ev[1],
                  ev[2]);
    f.fail(what);
  }
  return I;
}

// "mass" (kg), or "density" (kg/m^3) of the solid "box".
double payload_mass(const JsonField& f, const Eigen::Vector3d& box) {
  if (!f.has("density")) return f.at("mass").number_in({0, 1e4}, " kg");
  if (f.has("mass")) f.fail("give \"mass\" or \"density\", not both");
  if (!f.has("box")) f.at("density").fail("needs \"box\", the solid it is the density of");
  const double mass = f.at("density").number_in({0, 1e5}, " kg/m^3") * box.prod();
  if (mass > 1e4) f.at("density").fail("gives a mass above 10000 kg");
  return mass;
}

}  // namespace

Payload payload_from_json(const JsonField& f, const RobotModel& robot) {
  if (!f.value().is_object()) f.fail("expected an object with \"mass\" (kg)");
  f.allow_only({"mass", "density", "com", "inertia", "box", "link"});
  Payload p;
  p.link = link_field(f, robot);
  if (robot.links[p.link].body < 0)
    f.at("link").fail("'" + robot.links[p.link].name + "' does not move");
  if (f.has("inertia") && f.has("box")) f.fail("give \"inertia\" or \"box\", not both");
  if (f.has("box")) p.box = f.at("box").vec3_in({0, 10}, " m");
  p.mass = payload_mass(f, p.box);
  if (f.has("com")) p.com = f.at("com").vec3_in({-10, 10}, " m");
  if (f.has("inertia")) p.inertia = inertia_from_json(f.at("inertia"));
  if (f.has("box")) p.inertia = box_inertia(p.mass, p.box);
  return p;
}

RobotModel with_payload(const RobotModel& robot, const Payload& p) {
  RobotModel loaded = robot;
  if (!p.any()) return loaded;
  const Link& link = robot.links.at(p.link);
  const Pose& in_body = link.in_body;
  merge_inertia(loaded.bodies.at(link.body), p.mass, in_body * p.com,
                in_body.R * p.inertia * in_body.R.transpose());
  return loaded;
}

std::string payload_identity(const Payload& p) {
  if (!p.any()) return "";
  char text[512];
  const Eigen::Matrix3d& I = p.inertia;
  std::snprintf(text, sizeof text,
                "payload %d %.17g [%.17g %.17g %.17g] [%.17g %.17g %.17g %.17g %.17g %.17g]",
                p.link, p.mass, p.com.x(), p.com.y(), p.com.z(), I(0, 0), I(0, 1), I(0, 2), I(1, 1),
                I(1, 2), I(2, 2));
  return text;
}

}  // namespace lazyboe
