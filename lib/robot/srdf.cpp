#include "lazyboe/robot/srdf.h"

#include <tinyxml.h>

#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"

namespace lazyboe {
namespace {

std::string where(const std::string& path, const TiXmlElement* e) {
  return path + ":" + std::to_string(e->Row());
}

std::string required(const std::string& path, const TiXmlElement* e, const char* attribute) {
  const char* value = e->Attribute(attribute);
  if (!value || !*value) {
    fail(where(path, e), std::string("<") + e->Value() + "> needs " + attribute + "=\"...\"");
  }
  return value;
}

// The chain of `name`'s group (or of the first group with one when `name` is empty).
void read_group_chain(const std::string& path, const TiXmlElement* robot, const std::string& name,
                      SrdfDescription& out) {
  for (const TiXmlElement* g = robot->FirstChildElement("group"); g;
       g = g->NextSiblingElement("group")) {
    const std::string group = required(path, g, "name");
    if (!name.empty() && group != name) continue;
    const TiXmlElement* chain = g->FirstChildElement("chain");
    if (!chain) {
      if (name.empty()) continue;
      fail(where(path, g), "group '" + name + "' has no <chain> (only chain groups are planned)");
    }
    out.group = group;
    out.base_link = required(path, chain, "base_link");
    out.tip_link = required(path, chain, "tip_link");
    return;
  }
  if (!name.empty()) fail(path, "no group '" + name + "'");
}

}  // namespace

SrdfDescription read_srdf(const std::string& path, const std::string& group) {
  require_input_file(path, "SRDF file");
  TiXmlDocument xml;
  if (!xml.LoadFile(path)) {
    fail(path + ":" + std::to_string(xml.ErrorRow()),
         std::string("malformed XML (") + xml.ErrorDesc() + ")");
  }
  const TiXmlElement* robot = xml.RootElement();
  if (!robot || std::string(robot->Value()) != "robot") fail(path, "not an SRDF (no <robot>)");
  SrdfDescription out;
  read_group_chain(path, robot, group, out);
  for (const TiXmlElement* d = robot->FirstChildElement("disable_collisions"); d;
       d = d->NextSiblingElement("disable_collisions")) {
    const char* reason = d->Attribute("reason");
    out.disabled.push_back(
        {required(path, d, "link1"), required(path, d, "link2"), reason ? reason : ""});
  }
  for (const TiXmlElement* s = robot->FirstChildElement("group_state"); s;
       s = s->NextSiblingElement("group_state")) {
    const char* g = s->Attribute("group");
    if (out.group.empty() || (g && out.group == g)) out.poses.push_back(required(path, s, "name"));
  }
  return out;
}

}  // namespace lazyboe
