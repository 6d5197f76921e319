// Planner parameters, declared by each planner (OMPL's ParamSet in spirit): a name, a type, a
// default, an allowed range and one line of documentation. Values travel as numbers by name;
// make_planner (registry.h) checks them against the declarations and fills in the defaults.
#pragma once

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace lazyboe {

// Choice: one of `choices`, carried as its index (in JSON, the name).
enum class ParameterType { Real, Integer, Boolean, Choice };

struct ParameterSpec {
  std::string name;
  ParameterType type = ParameterType::Real;
  // NaN: no fixed default; the planner takes it from the planning context (default_from).
  double default_value = std::numeric_limits<double>::quiet_NaN();
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool lower_exclusive = false;      // (lower, upper] rather than [lower, upper]
  std::string description;           // one line
  std::string default_from;          // for a NaN default: where it comes from
  std::vector<std::string> choices;  // Choice: the names, in index order

  // Choice: the index of `name`, or -1.
  int choice_index(const std::string& name) const;

  bool has_fixed_default() const { return !std::isnan(default_value); }
  // "> 0", "[0, 1]", "any": the allowed range, as the errors and --list-planners show it.
  std::string range_text() const;
  // The default as shown to users: the number, or default_from.
  std::string default_text() const;
  // Empty when `value` is allowed, else why not ("must be > 0").
  std::string check(double value) const;
};

// A real parameter with a fixed default and a lower bound (exclusive or not).
ParameterSpec real_parameter(const std::string& name, double default_value, double lower,
                             bool lower_exclusive, const std::string& description);

// An integer parameter with a fixed default and inclusive bounds.
ParameterSpec integer_parameter(const std::string& name, double default_value, double lower,
                                double upper, const std::string& description);

// A boolean parameter (1 true, 0 false).
ParameterSpec boolean_parameter(const std::string& name, bool default_value,
                                const std::string& description);

// Values by parameter name.
class ParameterValues {
 public:
  ParameterValues() = default;
  ParameterValues(std::initializer_list<std::pair<const std::string, double>> values)
      : values_(values) {}

  void set(const std::string& name, double value) { values_[name] = value; }
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  // The value of a parameter; throws Error naming it when it is not set.
  double get(const std::string& name) const;
  double get_or(const std::string& name, double fallback) const {
    return has(name) ? values_.at(name) : fallback;
  }
  const std::map<std::string, double>& all() const { return values_; }

 private:
  std::map<std::string, double> values_;
};

}  // namespace lazyboe
