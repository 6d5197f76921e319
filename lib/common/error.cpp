#include "lazyboe/common/error.h"

namespace lazyboe {

void fail(const std::string& where, const std::string& what) {
  throw Error(where.empty() ? what : where + ": " + what);
}

}  // namespace lazyboe
