// The page's own HTML template, CSS and script (the files of viewer/), built into the library
// by CMake (lib/view/viewer_assets.cpp.in), so the tool needs only three.js at run time.
#pragma once

namespace lazyboe::viewer_assets {

extern const char* const html;
extern const char* const css;
extern const char* const js;

}  // namespace lazyboe::viewer_assets
