// Names for diagnostics: the "did you mean" candidate nearest to a misspelt name.
#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace sdfc {

// Levenshtein-nearest candidate within a small distance, or "" (for "did you mean").
std::string nearest_name(std::string_view name, const std::vector<std::string>& candidates);

}  // namespace sdfc
