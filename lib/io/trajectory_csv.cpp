#include "lazyboe/io/trajectory_csv.h"

#include <algorithm>
#include <fstream>

#include "lazyboe/common/error.h"
#include "lazyboe/io/csv.h"

namespace lazyboe {
namespace {

std::string trimmed(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

// The header row as read_numeric_csv splits it (first non-blank line, cells trimmed), and its
// line number.
std::vector<std::string> header_of(const std::string& path, int& line_no) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  std::string line;
  line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (trimmed(line).empty()) continue;
    std::vector<std::string> cells;
    size_t start = 0;
    while (true) {
      const size_t comma = line.find(',', start);
      cells.push_back(trimmed(line.substr(start, comma - start)));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    return cells;
  }
  return {};
}

}  // namespace

TrajectoryCsv read_trajectory_csv(const std::string& path, int dof) {
  std::vector<std::string> leading = {"t"};
  for (const char* p : {"q", "dq"}) {
    for (const std::string& c : numbered_columns(p, dof)) leading.push_back(c);
  }
  std::string expected;
  for (const std::string& c : leading) expected += (expected.empty() ? "" : ",") + c;
  int header_line = 0;
  const std::vector<std::string> header = header_of(path, header_line);
  if (header.empty()) fail(path, "empty file (expected header '" + expected + ",...')");
  if (header.size() < leading.size() ||
      !std::equal(leading.begin(), leading.end(), header.begin())) {
    fail(path + ":" + std::to_string(header_line),
         "header must start with '" + expected + "' (further columns optional)");
  }
  const CsvTable table = read_numeric_csv(path, header);  // every row and value checked
  if (table.rows.empty()) fail(path, "no samples after the header");

  TrajectoryCsv out;
  out.path = path;
  out.dof = dof;
  const size_t rows = table.rows.size();
  out.t.reserve(rows);
  out.q.reserve(rows * dof);
  out.dq.reserve(rows * dof);
  for (const std::vector<double>& r : table.rows) {
    out.t.push_back(r[0]);
    out.q.insert(out.q.end(), r.begin() + 1, r.begin() + 1 + dof);
    out.dq.insert(out.dq.end(), r.begin() + 1 + dof, r.begin() + 1 + 2 * dof);
  }
  out.line = table.line;
  return out;
}

}  // namespace lazyboe
