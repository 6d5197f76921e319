#include "lazyboe/common/json_fields.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "lazyboe/common/error.h"

namespace lazyboe {

nlohmann::json load_json_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) lazyboe::fail(path, "cannot open file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // nlohmann reports a byte offset; turn it into line:column for the user.
    size_t line = 1, column = 1;
    for (size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    lazyboe::fail(path + ":" + std::to_string(line) + ":" + std::to_string(column), "invalid JSON");
  }
}

JsonField::JsonField(const nlohmann::json& value, std::string file, std::string path)
    : value_(&value), file_(std::move(file)), path_(std::move(path)) {}

void JsonField::fail(const std::string& what) const {
  lazyboe::fail(file_ + (path_.empty() ? "" : ": " + path_), what);
}

bool JsonField::has(const std::string& key) const {
  return value_->is_object() && value_->contains(key);
}

JsonField JsonField::at(const std::string& key) const {
  if (!value_->is_object()) fail("expected an object");
  auto it = value_->find(key);
  const std::string child = path_.empty() ? key : path_ + "." + key;
  if (it == value_->end()) lazyboe::fail(file_ + ": " + child, "missing required field");
  return JsonField(*it, file_, child);
}

std::vector<JsonField> JsonField::items() const {
  if (!value_->is_array()) fail("expected an array");
  std::vector<JsonField> out;
  for (size_t i = 0; i < value_->size(); ++i) {
    out.emplace_back((*value_)[i], file_, path_ + "[" + std::to_string(i) + "]");
  }
  return out;
}

void JsonField::allow_only(std::initializer_list<const char*> keys) const {
  allow_only(std::vector<std::string>(keys.begin(), keys.end()));
}

void JsonField::allow_only(const std::vector<std::string>& keys) const {
  if (!value_->is_object()) fail("expected an object");
  for (auto it = value_->begin(); it != value_->end(); ++it) {
    bool known = false;
    for (const std::string& k : keys) known = known || it.key() == k;
    if (!known) {
      lazyboe::fail(file_ + ": " + (path_.empty() ? "" : path_ + ".") + it.key(), "unknown field");
    }
  }
}

double JsonField::number() const {
  if (!value_->is_number()) fail("expected a number");
  const double v = value_->get<double>();
  if (!std::isfinite(v)) fail("expected a finite number");
  return v;
}

double JsonField::number_at_least(double min) const {
  const double v = number();
  if (v < min) fail("must be >= " + std::to_string(min));
  return v;
}

double JsonField::positive() const {
  const double v = number();
  if (!(v > 0)) fail("must be > 0");
  return v;
}

long JsonField::integer() const {
  if (!value_->is_number_integer()) fail("expected an integer");
  return value_->get<long>();
}

bool JsonField::boolean() const {
  if (!value_->is_boolean()) fail("expected true or false");
  return value_->get<bool>();
}

std::string JsonField::string() const {
  if (!value_->is_string()) fail("expected a string");
  return value_->get<std::string>();
}

std::vector<double> JsonField::numbers() const {
  std::vector<double> out;
  for (const JsonField& item : items()) out.push_back(item.number());
  return out;
}

Eigen::Vector3d JsonField::vec3() const {
  const std::vector<double> v = numbers();
  if (v.size() != 3) fail("expected 3 numbers, got " + std::to_string(v.size()));
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

}  // namespace lazyboe
