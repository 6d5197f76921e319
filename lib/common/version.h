// The library's version (the CMake project version), as recorded in the files it writes.
#pragma once

namespace lazyboe {

const char* version();

}  // namespace lazyboe
