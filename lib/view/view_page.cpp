#include "lazyboe/view/view_page.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/view/viewer_assets.h"

#ifndef LAZYBOE_THREE_DIR
#define LAZYBOE_THREE_DIR "/usr/share/javascript/three"
#endif

namespace lazyboe {

std::string default_three_dir() {
  const char* env = std::getenv("LAZYBOE_THREE_DIR");
  return env && *env ? std::string(env) : std::string(LAZYBOE_THREE_DIR);
}

namespace {

std::string read_script(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (in) text << in.rdbuf();
  if (!in || text.str().empty())
    fail("three.js not found", path +
                                   ": cannot read (install Debian's libjs-three with "
                                   "scripts/install-deps.sh, or pass --three-dir)");
  return text.str();
}

// Text inside <script>: a "</" (as in "</script>") would end the element early; "<\/" reads
// the same in JSON and in JavaScript strings.
std::string script_safe(std::string text) {
  for (size_t at = text.find("</"); at != std::string::npos; at = text.find("</", at + 3))
    text.replace(at, 2, "<\\/");
  return text;
}

void substitute(std::string& page, const std::string& marker, const std::string& text) {
  const size_t at = page.find(marker);
  if (at == std::string::npos) fail("viewer template", "has no " + marker);
  page.replace(at, marker.size(), text);
}

}  // namespace

ViewerScripts load_viewer_scripts(const std::string& three_dir) {
  ViewerScripts s;
  s.three = read_script(three_dir + "/three.min.js");
  s.orbit_controls = read_script(three_dir + "/examples/js/controls/OrbitControls.js");
  if (s.three.find("</script") != std::string::npos ||
      s.orbit_controls.find("</script") != std::string::npos)
    fail(three_dir, "three.js contains '</script' and cannot be inlined");
  return s;
}

std::string viewer_page(const nlohmann::json& data, const ViewerScripts& scripts) {
  // Markers replaced in this order, each once; the data last, so text in it is never taken
  // for a marker.
  std::string page = viewer_assets::html;
  substitute(page, "/*@VIEWER_CSS@*/", viewer_assets::css);
  substitute(page, "/*@THREE_JS@*/", scripts.three);
  substitute(page, "/*@ORBIT_CONTROLS_JS@*/", scripts.orbit_controls);
  substitute(page, "/*@VIEWER_JS@*/", script_safe(viewer_assets::js));
  substitute(page, "/*@VIEWER_DATA@*/", script_safe(data.dump()));
  return page;
}

}  // namespace lazyboe
