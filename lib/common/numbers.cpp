#include "lazyboe/common/numbers.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

// [+-] digits [. digits] [(e|E) [+-] digits], at least one mantissa digit.
bool plain_decimal_syntax(const std::string& s) {
  size_t i = 0;
  const auto digits = [&] {
    const size_t from = i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
    return i - from;
  };
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  size_t mantissa = digits();
  if (i < s.size() && s[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == s.size();
}

}  // namespace

bool RealRange::contains(double v) const {
  return (open_low ? v > low : v >= low) && (open_high ? v < high : v <= high);
}

std::string RealRange::text() const {
  return std::string(open_low ? "(" : "[") + number_text(low) + ", " + number_text(high) +
         (open_high ? ")" : "]");
}

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

bool parse_decimal(const std::string& text, double& value) {
  if (!plain_decimal_syntax(text)) return false;
  const double v = std::strtod(text.c_str(), nullptr);  // underflow to 0 or a denormal is fine
  if (!std::isfinite(v)) return false;
  value = v;
  return true;
}

void check_in_range(double value, const RealRange& range, const std::string& where,
                    const std::string& unit) {
  if (!std::isfinite(value)) fail(where, "must be a finite number in " + range.text() + unit);
  if (!range.contains(value))
    fail(where, number_text(value) + " is outside the accepted range " + range.text() + unit);
}

double parse_real_in(const std::string& text, const RealRange& range, const std::string& where,
                     const std::string& unit) {
  double v = 0;
  if (!parse_decimal(text, v))
    fail(where, "'" + text + "' is not a number (accepted: finite decimal numbers in " +
                    range.text() + unit + ")");
  check_in_range(v, range, where, unit);
  return v;
}

}  // namespace lazyboe
