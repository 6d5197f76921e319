// The numeric CSV tables of lazyboe-robot (read_numeric_csv): `torques --in` (q, dq, ddq of the
// Panda, cells within 1e6) when the input's first byte is even, `check --in` (q1..q7, within
// 1e3) when it is odd; the rest of the input is the file.
#include "fuzz_util.h"
#include "lazyboe/common/error.h"
#include "lazyboe/io/csv.h"

using namespace lazyboe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const std::vector<std::string> check_header = numbered_columns("q", 7);
  static const std::vector<std::string> torques_header = [] {
    std::vector<std::string> h = numbered_columns("q", 7);
    for (const char* prefix : {"dq", "ddq"}) {
      const std::vector<std::string> more = numbered_columns(prefix, 7);
      h.insert(h.end(), more.begin(), more.end());
    }
    return h;
  }();
  const bool check = data[0] & 1;
  const std::string path = fuzz::write_scratch("table.csv", data + 1, size - 1);
  try {
    const CsvTable table = check ? read_numeric_csv(path, check_header, {-1e3, 1e3})
                                 : read_numeric_csv(path, torques_header, {-1e6, 1e6});
    (void)table;
  } catch (const Error&) {
    // Refused with a message: expected. Anything else is a finding.
  }
  return 0;
}
