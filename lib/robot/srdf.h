// What a MoveIt SRDF says that a robot config uses: a planning group's chain and the link pairs
// whose collisions are disabled (<disable_collisions link1= link2= reason=/>).
#pragma once

#include <string>
#include <vector>

namespace lazyboe {

struct SrdfPair {
  std::string link1, link2, reason;
};

struct SrdfDescription {
  std::string group;                // the group whose chain was read; empty: none
  std::string base_link, tip_link;  // its <chain>
  std::vector<SrdfPair> disabled;   // every <disable_collisions>
  std::vector<std::string> poses;   // names of the group's <group_state>s (not used yet)
};

// Reads `path`; `group` names the planning group (empty: the first group with a <chain>).
// Throws Error("<path>:<line>: ...") for malformed XML, a named group that is missing or has no
// chain, and elements without their attributes.
SrdfDescription read_srdf(const std::string& path, const std::string& group);

}  // namespace lazyboe
