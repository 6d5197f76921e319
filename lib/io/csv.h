// Numeric CSV tables with a header row, as the tools read and write them. Every value is
// checked: a wrong column count, text, NaN or infinity is an error naming file, line and column.
#pragma once

#include <string>
#include <vector>

#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/numbers.h"

namespace lazyboe {

struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  std::vector<int> line;  // source line of each row, for messages
};

// Reads a CSV whose header must equal `expected_header` exactly. Every cell is a plain decimal
// number ("0x10", "inf", "1e400" are refused) within `range`.
CsvTable read_numeric_csv(const std::string& path, const std::vector<std::string>& expected_header,
                          const RealRange& range = {-1e9, 1e9});

// Column names like q1..qn.
std::vector<std::string> numbered_columns(const std::string& prefix, int n);

// Writes a CSV by temporary file and rename, so an interrupted run never leaves half a file.
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::vector<std::string>& header);
  void row(const std::vector<double>& values);
  void commit();  // flush and rename into place (uncommitted: the partial file is dropped)

 private:
  AtomicFile file_;
  size_t columns_;
};

}  // namespace lazyboe
