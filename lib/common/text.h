// Lists in messages: "a, b or c".
#pragma once

#include <string>
#include <vector>

namespace lazyboe {

// The items separated by ", ", the last two by `last` (" or ", or ", " for a plain list).
inline std::string list_text(const std::vector<std::string>& items,
                             const std::string& last = " or ") {
  std::string text;
  for (size_t k = 0; k < items.size(); ++k)
    text += (k == 0 ? "" : k + 1 == items.size() ? last : ", ") + items[k];
  return text;
}

}  // namespace lazyboe
