// lazyboe-bench's runs.csv and runs.partial.csv as --resume reads them (read_runs_csv), then
// written back as the resumed study does, and read once more: what was accepted once must
// read back the same.
#include <cstdlib>

#include "fuzz_util.h"
#include "lazyboe/bench/report.h"
#include "lazyboe/common/error.h"

using namespace lazyboe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // The problem ids of the seed corpus (tests/data/bench-runs.csv and lazyboe-bench's p<k>).
  static const std::vector<std::string> ids = {"synthetic-1", "synthetic-2", "p0", "p1", "p2"};
  const std::string path = fuzz::write_scratch("runs.partial.csv", data, size);
  std::vector<RunRecord> runs;
  try {
    runs = read_runs_csv(path, ids);
  } catch (const Error&) {
    return 0;  // refused with a message: expected
  }
  const std::string again = fuzz::scratch_dir() + "/runs.csv";
  write_runs_csv(again, runs, ids);
  const std::vector<RunRecord> reread = read_runs_csv(again, ids);  // must not throw
  if (reread.size() != runs.size()) std::abort();
  return 0;
}
