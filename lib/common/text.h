// Lists in messages ("a, b or c") and suggestions for a misspelt name ("did you mean ...?").
#pragma once

#include <algorithm>
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

// Levenshtein distance (insertions, deletions, substitutions), case-sensitive.
inline size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// " (did you mean 'x'?)" for the closest of `known` within a third of the name's length (at
// least 1 edit, at most 3), or "" when none is that close.
inline std::string did_you_mean(const std::string& name, const std::vector<std::string>& known) {
  const size_t limit = std::min<size_t>(3, std::max<size_t>(1, name.size() / 3));
  const std::string* best = nullptr;
  size_t best_distance = limit + 1;
  for (const std::string& k : known) {
    const size_t d = edit_distance(name, k);
    if (d < best_distance) best = &k, best_distance = d;
  }
  return best ? " (did you mean '" + *best + "'?)" : "";
}

}  // namespace lazyboe
