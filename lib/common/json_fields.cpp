#include "lazyboe/common/json_fields.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/common/text.h"

namespace lazyboe {

namespace {

using nlohmann::json;

// "line:column" of a byte offset.
std::string position_text(const std::string& text, size_t byte) {
  size_t line = 1, column = 1;
  for (size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return std::to_string(line) + ":" + std::to_string(column);
}

// nlohmann's DOM builder, refusing a key repeated within one object (nlohmann keeps the last
// value without a word). It tracks the path of the value being read for the message.
class StrictSax {
 public:
  StrictSax(json& root, std::string text_where, const std::string& text, bool with_position)
      : dom_(root), where_(std::move(text_where)), text_(text), with_position_(with_position) {}

  bool null() { return value() && dom_.null(); }
  bool boolean(bool v) { return value() && dom_.boolean(v); }
  bool number_integer(json::number_integer_t v) { return value() && dom_.number_integer(v); }
  bool number_unsigned(json::number_unsigned_t v) { return value() && dom_.number_unsigned(v); }
  bool number_float(json::number_float_t v, const json::string_t& s) {
    return value() && dom_.number_float(v, s);
  }
  bool string(json::string_t& v) { return value() && dom_.string(v); }
  bool binary(json::binary_t& v) { return value() && dom_.binary(v); }
  bool start_object(std::size_t n) {
    value();
    frames_.push_back({false, 0, "", {}});
    return dom_.start_object(n);
  }
  bool key(json::string_t& k) {
    Frame& f = frames_.back();
    f.key = k;
    if (!f.keys.insert(k).second)
      lazyboe::fail(where_ + (path().empty() ? "" : ": " + path()),
                    "duplicate key '" + k + "' (each key may appear once in an object)");
    return dom_.key(k);
  }
  bool end_object() {
    frames_.pop_back();
    return dom_.end_object();
  }
  bool start_array(std::size_t n) {
    value();
    frames_.push_back({true, 0, "", {}});
    return dom_.start_array(n);
  }
  bool end_array() {
    frames_.pop_back();
    return dom_.end_array();
  }
  bool parse_error(std::size_t byte, const std::string& token,
                   const nlohmann::detail::exception& e) {
    const std::string where = with_position_ ? where_ + ":" + position_text(text_, byte) : where_;
    if (e.id == 406) lazyboe::fail(where, "number out of range ('" + token + "')");
    lazyboe::fail(where, with_position_ ? "invalid JSON" : "not valid JSON");
  }

 private:
  struct Frame {
    bool array;
    size_t index;
    std::string key;
    std::set<std::string> keys;
  };
  // Every value event: an element of an array advances its index.
  bool value() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    return true;
  }
  // The enclosing object's path, as JsonField spells it ("objects[2]"): the duplicate is a key
  // of the innermost object.
  std::string path() const {
    std::string p;
    for (size_t i = 0; i + 1 < frames_.size(); ++i) {
      const Frame& f = frames_[i];
      p += f.array ? "[" + std::to_string(f.index - 1) + "]" : (p.empty() ? "" : ".") + f.key;
    }
    return p;
  }

  nlohmann::detail::json_sax_dom_parser<json> dom_;
  std::string where_;
  const std::string& text_;
  bool with_position_;
  std::vector<Frame> frames_;
};

}  // namespace

nlohmann::json parse_json_text(const std::string& text, const std::string& where,
                               bool with_position) {
  json root;
  StrictSax sax(root, where, text, with_position);
  json::sax_parse(text, &sax);
  return root;
}

nlohmann::json load_json_file(const std::string& path) {
  require_input_file(path);
  std::ifstream in(path);
  if (!in) lazyboe::fail(path, "cannot open file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_json_text(buffer.str(), path, true);
}

JsonField::JsonField(const nlohmann::json& value, std::string file, std::string path)
    : value_(&value), file_(std::move(file)), path_(std::move(path)) {}

void JsonField::fail(const std::string& what) const { lazyboe::fail(where(), what); }

bool JsonField::has(const std::string& key) const {
  return value_->is_object() && value_->contains(key);
}

JsonField JsonField::at(const std::string& key) const {
  if (!value_->is_object()) fail("expected an object");
  auto it = value_->find(key);
  const std::string child = path_.empty() ? key : path_ + "." + key;
  if (it == value_->end())
    lazyboe::fail(JsonField(*value_, file_, child).where(), "missing required field");
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
      const JsonField field(it.value(), file_, path_.empty() ? it.key() : path_ + "." + it.key());
      field.fail("unknown field" + did_you_mean(it.key(), keys));
    }
  }
}

double JsonField::number() const {
  if (!value_->is_number()) fail("expected a number");
  const double v = value_->get<double>();
  if (!std::isfinite(v)) fail("expected a finite number");
  return v;
}

double JsonField::number_in(const RealRange& range, const std::string& unit) const {
  if (!value_->is_number()) fail("expected a number in " + range.text() + unit);
  const double v = value_->get<double>();
  if (!std::isfinite(v) || !range.contains(v))
    fail(number_text(v) + " is outside the accepted range " + range.text() + unit);
  return v;
}

Eigen::Vector3d JsonField::vec3_in(const RealRange& range, const std::string& unit) const {
  const std::vector<JsonField> v = items();
  if (v.size() != 3) fail("expected 3 numbers, got " + std::to_string(v.size()));
  return Eigen::Vector3d(v[0].number_in(range, unit), v[1].number_in(range, unit),
                         v[2].number_in(range, unit));
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
