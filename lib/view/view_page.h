// The self-contained viewer page: the page's own HTML, CSS and script (viewer/, built into the
// library) and three.js with its OrbitControls (Debian's libjs-three, read from disk), all
// inlined with the scene data into one HTML file that opens without a server or a network.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace lazyboe {

// Where three.js is looked for: LAZYBOE_THREE_DIR in the environment, else the directory the
// build was configured with (CMake's LAZYBOE_THREE_DIR, /usr/share/javascript/three).
std::string default_three_dir();

struct ViewerScripts {
  std::string three;           // three.min.js
  std::string orbit_controls;  // examples/js/controls/OrbitControls.js
};

// Throws Error("three.js not found: <file>: ...") naming the missing file and how to install it.
ViewerScripts load_viewer_scripts(const std::string& three_dir);

// The page's HTML with every script and the data inlined.
std::string viewer_page(const nlohmann::json& data, const ViewerScripts& scripts);

}  // namespace lazyboe
