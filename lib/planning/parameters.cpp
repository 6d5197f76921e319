#include "lazyboe/planning/parameters.h"

#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/common/text.h"

namespace lazyboe {
namespace {

std::string number_text(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

}  // namespace

int ParameterSpec::choice_index(const std::string& key) const {
  for (size_t k = 0; k < choices.size(); ++k)
    if (choices[k] == key) return static_cast<int>(k);
  return -1;
}

std::string ParameterSpec::range_text() const {
  if (type == ParameterType::Boolean) return "true or false";
  if (type == ParameterType::Choice) return list_text(choices);
  const bool has_lower = std::isfinite(lower), has_upper = std::isfinite(upper);
  if (has_lower && has_upper) {
    return std::string(lower_exclusive ? "(" : "[") + number_text(lower) + ", " +
           number_text(upper) + "]";
  }
  if (has_lower) return std::string(lower_exclusive ? "> " : ">= ") + number_text(lower);
  if (has_upper) return "<= " + number_text(upper);
  return "any";
}

std::string ParameterSpec::default_text() const {
  if (!has_fixed_default()) return default_from;
  if (type == ParameterType::Boolean) return default_value != 0 ? "true" : "false";
  if (type == ParameterType::Choice) return choices.at(static_cast<size_t>(default_value));
  return number_text(default_value);
}

std::string ParameterSpec::check(double value) const {
  if (!std::isfinite(value)) return "must be a finite number";
  if (type == ParameterType::Boolean && value != 0 && value != 1) return "must be true or false";
  if (type == ParameterType::Integer && value != std::floor(value)) return "must be an integer";
  if (type == ParameterType::Choice) {
    const bool known = value >= 0 && value < choices.size() && value == std::floor(value);
    return known ? "" : "must be " + range_text();
  }
  const bool below = lower_exclusive ? !(value > lower) : !(value >= lower);
  if (below || value > upper) {
    const bool interval = std::isfinite(lower) && std::isfinite(upper);
    return std::string("must be ") + (interval ? "in " : "") + range_text();
  }
  return "";
}

ParameterSpec real_parameter(const std::string& name, double default_value, double lower,
                             bool lower_exclusive, const std::string& description) {
  ParameterSpec p;
  p.name = name;
  p.default_value = default_value;
  p.lower = lower;
  p.lower_exclusive = lower_exclusive;
  p.description = description;
  return p;
}

ParameterSpec integer_parameter(const std::string& name, double default_value, double lower,
                                double upper, const std::string& description) {
  ParameterSpec p = real_parameter(name, default_value, lower, false, description);
  p.type = ParameterType::Integer;
  p.upper = upper;
  return p;
}

ParameterSpec boolean_parameter(const std::string& name, bool default_value,
                                const std::string& description) {
  ParameterSpec p;
  p.name = name;
  p.type = ParameterType::Boolean;
  p.default_value = default_value ? 1 : 0;
  p.description = description;
  return p;
}

double ParameterValues::get(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end()) fail(name, "parameter not set");
  return it->second;
}

}  // namespace lazyboe
