#include "lazyboe/io/csv.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"

namespace lazyboe {
namespace {

std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) out += (i ? "," : "") + v[i];
  return out;
}

}  // namespace

std::vector<std::string> numbered_columns(const std::string& prefix, int n) {
  std::vector<std::string> out;
  for (int i = 1; i <= n; ++i) out.push_back(prefix + std::to_string(i));
  return out;
}

CsvTable read_numeric_csv(const std::string& path, const std::vector<std::string>& expected_header,
                          const RealRange& range) {
  require_input_file(path);
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  CsvTable table;
  std::string line;
  int line_no = 0;
  bool have_header = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (trim(line).empty()) continue;
    const std::vector<std::string> cells = split(line);
    const std::string where = path + ":" + std::to_string(line_no);
    if (!have_header) {
      if (cells != expected_header) {
        fail(where, "header must be '" + join(expected_header) + "' (got '" + trim(line) + "')");
      }
      table.header = cells;
      have_header = true;
      continue;
    }
    if (cells.size() != expected_header.size()) {
      fail(where, "expected " + std::to_string(expected_header.size()) + " columns, got " +
                      std::to_string(cells.size()));
    }
    std::vector<double> row(cells.size());
    for (size_t c = 0; c < cells.size(); ++c) {
      row[c] = parse_real_in(cells[c], range, where + ": column '" + expected_header[c] + "'");
    }
    table.rows.push_back(std::move(row));
    table.line.push_back(line_no);
  }
  if (!have_header) fail(path, "empty file (expected header '" + join(expected_header) + "')");
  return table;
}

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& header)
    : file_(path), columns_(header.size()) {
  file_.stream() << join(header) << '\n';
}

void CsvWriter::row(const std::vector<double>& values) {
  if (values.size() != columns_)
    fail(file_.path(), "internal error: row width differs from header");
  std::ostream& out = file_.stream();
  char cell[32];
  for (size_t i = 0; i < values.size(); ++i) {
    std::snprintf(cell, sizeof cell, "%.10g", values[i]);
    out << cell << (i + 1 < values.size() ? ',' : '\n');
  }
}

void CsvWriter::commit() { file_.commit(); }

}  // namespace lazyboe
