// The URDF checked before urdfdom reads it: urdfdom turns a malformed number into 0 (or its
// parsed prefix) without a word, and reports every joint problem as one message that names no
// joint. Here every numeric attribute is parsed strictly and range-checked, and each joint's
// type, <limit> and numbers are checked, naming the file, line, link or joint and the range.
#pragma once

#include <string>

namespace lazyboe {

// Throws Error("<path>:<line>: link 'l' <inertia ixx>: '0.7x' is not a number (accepted:
// finite decimal numbers in [-1e+05, 1e+05] kg m^2)") and the like. `xml_text` must be well-formed
// XML.
void check_urdf_values(const std::string& xml_text, const std::string& path);

// "the joints form a loop through link 'l' (a URDF must be a tree)": the check above and the
// chain walk of load_robot say it the same way.
std::string urdf_loop_message(const std::string& link);

}  // namespace lazyboe
