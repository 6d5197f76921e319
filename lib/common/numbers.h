// Strict numbers from text (files and the command line): the whole token in plain decimal
// notation ("0x10", "4.97abc", "inf", "nan" and "" are not numbers), finite, and within the
// range the field allows. Messages name the field and the accepted range.
#pragma once

#include <cstdint>
#include <string>

namespace lazyboe {

// An interval of accepted values; `open_low` / `open_high` exclude the ends.
struct RealRange {
  double low, high;
  bool open_low = false, open_high = false;
  bool contains(double v) const;
  std::string text() const;  // "[0, 1e+06]", "(0, 1]"
};

// True when `text` is a number in plain decimal notation (optional sign, digits with an
// optional point, optional exponent) that is finite as a double; `value` receives it.
bool parse_decimal(const std::string& text, double& value);

// parse_decimal, then the range: throws Error("<where>: ...") naming the text and the range.
double parse_real_in(const std::string& text, const RealRange& range, const std::string& where,
                     const std::string& unit = "");

// The range check alone, for a value already parsed (JSON numbers, URDF values).
void check_in_range(double value, const RealRange& range, const std::string& where,
                    const std::string& unit = "");

// The shortest text of a number ("1e+06", "0.5").
std::string number_text(double v);

}  // namespace lazyboe
