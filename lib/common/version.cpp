#include "lazyboe/common/version.h"

namespace lazyboe {

const char* version() { return LAZYBOE_VERSION; }

}  // namespace lazyboe
