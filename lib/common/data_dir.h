// Where the bundled data (robots, scenes, sample queries) is.
#pragma once

#include <string>

namespace lazyboe {

// The bundled data directory: LAZYBOE_DATA_DIR in the environment; else an installed copy
// beside the running tool or Python module (<prefix>/share/lazyboe); else the source tree's
// data/ (a build tree); else the install prefix's share/lazyboe (a program of the user's linked
// with the installed library).
std::string data_dir();

}  // namespace lazyboe
