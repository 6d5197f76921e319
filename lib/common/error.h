// The one exception type of the library: a one-line message that names the file, line or
// field at fault. Tools print it and exit non-zero.
#pragma once

#include <stdexcept>
#include <string>

namespace lazyboe {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws Error("<where>: <what>").
[[noreturn]] void fail(const std::string& where, const std::string& what);

}  // namespace lazyboe
