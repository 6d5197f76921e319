#include "lazyboe/robot/urdf_check.h"

#include <tinyxml.h>

#include <cstring>
#include <map>
#include <sstream>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/common/numbers.h"

namespace lazyboe {
namespace {

// The numeric attributes of the URDF elements urdfdom reads, with the number of values and the
// accepted range of each (docs/reliability.md lists them). Ranges are physical bounds wide
// enough for any real robot, narrow enough that no product of them overflows.
struct NumericAttribute {
  const char* element;
  const char* attribute;
  int count;
  RealRange range;
  const char* unit;
};

constexpr double kMaxLength = 100;    // m: link offsets, collision geometry
constexpr double kMaxAngle = 100;     // rad: rpy (any angle, written unwrapped)
constexpr double kMaxMass = 1e5;      // kg
constexpr double kMaxInertia = 1e5;   // kg m^2
constexpr double kMaxPosition = 1e3;  // joint limits, rad or m
constexpr double kMaxVelocity = 1e4;  // rad/s or m/s
constexpr double kMaxEffort = 1e7;    // N m or N
constexpr double kMaxDynamics = 1e6;  // damping, friction

const std::vector<NumericAttribute>& numeric_attributes() {
  static const std::vector<NumericAttribute> table = {
      {"origin", "xyz", 3, {-kMaxLength, kMaxLength}, " m"},
      {"origin", "rpy", 3, {-kMaxAngle, kMaxAngle}, " rad"},
      {"mass", "value", 1, {0, kMaxMass}, " kg"},
      {"inertia", "ixx", 1, {-kMaxInertia, kMaxInertia}, " kg m^2"},
      {"inertia", "ixy", 1, {-kMaxInertia, kMaxInertia}, " kg m^2"},
      {"inertia", "ixz", 1, {-kMaxInertia, kMaxInertia}, " kg m^2"},
      {"inertia", "iyy", 1, {-kMaxInertia, kMaxInertia}, " kg m^2"},
      {"inertia", "iyz", 1, {-kMaxInertia, kMaxInertia}, " kg m^2"},
      {"inertia", "izz", 1, {-kMaxInertia, kMaxInertia}, " kg m^2"},
      {"axis", "xyz", 3, {-1e3, 1e3}, ""},
      {"limit", "lower", 1, {-kMaxPosition, kMaxPosition}, " rad or m"},
      {"limit", "upper", 1, {-kMaxPosition, kMaxPosition}, " rad or m"},
      {"limit", "velocity", 1, {0, kMaxVelocity}, " rad/s or m/s"},
      {"limit", "effort", 1, {0, kMaxEffort}, " N m or N"},
      {"dynamics", "damping", 1, {0, kMaxDynamics}, ""},
      {"dynamics", "friction", 1, {0, kMaxDynamics}, ""},
      {"box", "size", 3, {0, kMaxLength, true}, " m"},
      {"cylinder", "radius", 1, {0, kMaxLength, true}, " m"},
      {"cylinder", "length", 1, {0, kMaxLength, true}, " m"},
      {"sphere", "radius", 1, {0, kMaxLength, true}, " m"},
      {"mesh", "scale", 3, {-1e3, 1e3}, ""},
      {"color", "rgba", 4, {0, 1}, ""},
      {"mimic", "multiplier", 1, {-1e3, 1e3}, ""},
      {"mimic", "offset", 1, {-kMaxPosition, kMaxPosition}, ""},
      {"safety_controller", "soft_lower_limit", 1, {-kMaxPosition, kMaxPosition}, ""},
      {"safety_controller", "soft_upper_limit", 1, {-kMaxPosition, kMaxPosition}, ""},
      {"safety_controller", "k_position", 1, {-1e9, 1e9}, ""},
      {"safety_controller", "k_velocity", 1, {-1e9, 1e9}, ""},
      {"calibration", "rising", 1, {-kMaxPosition, kMaxPosition}, ""},
      {"calibration", "falling", 1, {-kMaxPosition, kMaxPosition}, ""},
  };
  return table;
}

// "link 'panda_link3'" or "joint 'panda_joint2'": the nearest enclosing link or joint.
std::string owner_of(const TiXmlElement* e) {
  for (const TiXmlNode* n = e; n; n = n->Parent()) {
    const TiXmlElement* el = n->ToElement();
    if (!el) continue;
    const std::string tag = el->Value();
    if (tag == "link" || tag == "joint") {
      const char* name = el->Attribute("name");
      return tag + " '" + (name ? name : "?") + "'";
    }
  }
  return "robot";
}

std::string where_of(const std::string& path, const TiXmlElement* e) {
  return path + ":" + std::to_string(e->Row()) + ": " + owner_of(e);
}

void check_attribute(const std::string& path, const TiXmlElement* e, const NumericAttribute& a) {
  const char* text = e->Attribute(a.attribute);
  if (!text) return;  // absence is urdfdom's business (defaults or its own error)
  const std::string where = where_of(path, e) + " <" + a.element + " " + a.attribute + ">";
  std::istringstream in(text);
  std::vector<std::string> tokens;
  for (std::string t; in >> t;) tokens.push_back(t);
  if (static_cast<int>(tokens.size()) != a.count)
    fail(where, "'" + std::string(text) + "': expected " + std::to_string(a.count) +
                    (a.count == 1 ? " number" : " numbers"));
  for (const std::string& t : tokens) parse_real_in(t, a.range, where, a.unit);
}

void check_joint(const std::string& path, const TiXmlElement* joint) {
  const std::string where = where_of(path, joint);
  const char* type_text = joint->Attribute("type");
  if (!type_text) fail(where, "missing type");
  const std::string type = type_text;
  static const char* const kTypes[] = {"revolute", "continuous", "prismatic",
                                       "fixed",    "floating",   "planar"};
  bool known = false;
  for (const char* t : kTypes) known = known || type == t;
  if (!known)
    fail(where, "unknown joint type '" + type +
                    "' (URDF has revolute, continuous, prismatic, fixed, floating and planar)");
  if (!joint->FirstChildElement("parent") || !joint->FirstChildElement("child"))
    fail(where, "needs a <parent link=...> and a <child link=...>");
  if ((type == "revolute" || type == "prismatic") && !joint->FirstChildElement("limit"))
    fail(where, "missing <limit> (required for " + type + " joints)");
}

void walk(const std::string& path, const TiXmlElement* e) {
  for (; e; e = e->NextSiblingElement()) {
    const char* tag = e->Value();
    for (const NumericAttribute& a : numeric_attributes()) {
      if (std::strcmp(tag, a.element) == 0) check_attribute(path, e, a);
    }
    if (std::strcmp(tag, "joint") == 0 && e->Parent() && e->Parent()->ToElement() &&
        std::strcmp(e->Parent()->ToElement()->Value(), "robot") == 0)
      check_joint(path, e);
    walk(path, e->FirstChildElement());
  }
}

// The joints must make a tree: each link the child of at most one joint, and no loop. urdfdom
// checks neither: a link with two parents or a loop of joints is linked into a cycle of owning
// pointers (never freed, even when urdfdom then fails for want of a single root), and walking
// up a loop never ends (found by fuzzing).
void check_tree(const std::string& path, const TiXmlElement* robot) {
  struct ParentJoint {
    std::string parent;
    const TiXmlElement* joint;
  };
  std::map<std::string, ParentJoint> parent_of;  // child link -> its joint
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j;
       j = j->NextSiblingElement("joint")) {
    const TiXmlElement* p = j->FirstChildElement("parent");
    const TiXmlElement* c = j->FirstChildElement("child");
    const char* parent = p ? p->Attribute("link") : nullptr;
    const char* child = c ? c->Attribute("link") : nullptr;
    if (!parent || !child) continue;  // urdfdom reports it
    if (std::strcmp(parent, child) == 0)
      fail(where_of(path, j), "link '" + std::string(child) + "' is its own parent");
    const auto [it, added] = parent_of.emplace(child, ParentJoint{parent, j});
    if (!added) {
      const char* other = it->second.joint->Attribute("name");
      fail(where_of(path, j), "link '" + std::string(child) + "' is already the child of joint '" +
                                  (other ? other : "?") + "' (a URDF must be a tree)");
    }
  }
  for (const auto& [start, first] : parent_of) {
    std::string link = start;
    for (size_t steps = 0;; ++steps) {
      const auto up = parent_of.find(link);
      if (up == parent_of.end()) break;
      if (steps > parent_of.size()) fail(where_of(path, first.joint), urdf_loop_message(start));
      link = up->second.parent;
    }
  }
}

}  // namespace

std::string urdf_loop_message(const std::string& link) {
  return "the joints form a loop through link '" + link + "' (a URDF must be a tree)";
}

void check_urdf_values(const std::string& xml_text, const std::string& path) {
  TiXmlDocument xml;
  xml.Parse(xml_text.c_str());
  if (xml.Error() || !xml.RootElement()) return;  // reported by the caller
  walk(path, xml.RootElement());
  // The <robot> urdfdom reads: the first top-level element of that name, which need not be the
  // document's first element (a stray element before it; found by fuzzing).
  if (const TiXmlElement* robot = xml.FirstChildElement("robot")) check_tree(path, robot);
}

}  // namespace lazyboe
