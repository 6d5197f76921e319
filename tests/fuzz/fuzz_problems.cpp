// A lazyboe-bench problems file (problems.jsonl, read by --problems-file and by --resume):
// read_problems with the bundled Panda on the table, then written back as a new study does.
#include "lazyboe/bench/problems.h"
#include "lazyboe/common/error.h"
#include "table_scene.h"

using namespace lazyboe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::TableScene& scene = fuzz::table_scene();
  const std::string path = fuzz::write_scratch("problems.jsonl", data, size);
  try {
    const std::vector<BenchProblem> problems =
        read_problems(path, scene.sim, scene.ws, QueryDefaults{});
    write_problems(fuzz::scratch_dir() + "/problems-out.jsonl", scene.robot, problems);
  } catch (const Error&) {
    // Refused with a message: expected. Anything else is a finding.
  }
  return 0;
}
