// One lazyboe-query line (JSON, schemas/query.schema.json): parse_query with the bundled Panda
// on the table, then the error result the tool writes for a refused line.
#include "lazyboe/common/error.h"
#include "lazyboe/io/query_io.h"
#include "table_scene.h"

using namespace lazyboe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::TableScene& scene = fuzz::table_scene();
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::string id;
  try {
    const Query q = parse_query(text, 1, scene.sim, scene.ws, QueryDefaults{}, id);
    (void)q;
  } catch (const Error& e) {
    // lazyboe-query answers a refused line with this result line; it must serialize.
    (void)error_json(id, 1, "", e.what()).dump();
  }
  return 0;
}
