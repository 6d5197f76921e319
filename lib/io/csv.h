// Numeric CSV tables with a header row, as the tools read and write them. Every value is
// checked: a wrong column count, text, NaN or infinity is an error naming file, line and column.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace lazyboe {

struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  std::vector<int> line;  // source line of each row, for messages
};

// Reads a CSV whose header must equal `expected_header` exactly.
CsvTable read_numeric_csv(const std::string& path, const std::vector<std::string>& expected_header);

// Column names like q1..qn.
std::vector<std::string> numbered_columns(const std::string& prefix, int n);

// Writes a CSV by temporary file and rename, so an interrupted run never leaves half a file.
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::vector<std::string>& header);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  void row(const std::vector<double>& values);
  void commit();  // flush and rename into place

 private:
  std::string path_, tmp_path_;
  std::FILE* file_ = nullptr;
  size_t columns_;
};

}  // namespace lazyboe
