// Reading JSON input files with errors that name the file and the field path
// (for example "table.json: objects[2].size: expected 3 numbers").
#pragma once

#include <Eigen/Core>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace lazyboe {

struct RealRange;

// Parses a whole JSON file; a syntax error or a number out of range names the line and column,
// a key repeated within one object (which JSON parsers resolve differently) names the key and
// where it is. A directory or a missing file is named as such.
nlohmann::json load_json_file(const std::string& path);

// The same for text held in memory; `where` starts the messages ("line 3"). With
// `with_position`, syntax errors add ":line:column" to `where`.
nlohmann::json parse_json_text(const std::string& text, const std::string& where,
                               bool with_position);

// A view of one JSON value with the file and path it came from.
class JsonField {
 public:
  JsonField(const nlohmann::json& value, std::string file, std::string path);

  const std::string& path() const { return path_; }
  // "file: path" (or the file alone at the root), as the errors start.
  std::string where() const {
    return path_.empty() ? file_ : file_.empty() ? path_ : file_ + ": " + path_;
  }
  const nlohmann::json& value() const { return *value_; }
  [[noreturn]] void fail(const std::string& what) const;

  bool has(const std::string& key) const;
  JsonField at(const std::string& key) const;  // required member
  std::vector<JsonField> items() const;        // elements of an array
  // Rejects members other than these, so a misspelt optional field is not silently ignored.
  void allow_only(std::initializer_list<const char*> keys) const;
  void allow_only(const std::vector<std::string>& keys) const;

  double number() const;  // finite
  // A finite number within `range`; the message names the range (and `unit`, e.g. " m").
  double number_in(const RealRange& range, const std::string& unit = "") const;
  Eigen::Vector3d vec3_in(const RealRange& range, const std::string& unit = "") const;
  double number_at_least(double min) const;
  double positive() const;
  long integer() const;
  bool boolean() const;
  std::string string() const;
  Eigen::Vector3d vec3() const;
  std::vector<double> numbers() const;

 private:
  const nlohmann::json* value_;
  std::string file_;
  std::string path_;
};

}  // namespace lazyboe
