#include "compiler/base/names.hpp"

#include <algorithm>

namespace sdfc {

std::string nearest_name(std::string_view name, const std::vector<std::string>& candidates) {
    std::string best;
    if (name.empty() || name.size() > 64) return best;  // no typo of a known name; keeps this cheap
    // Edit distance in half steps: a letter of the wrong case costs 1, any other edit 2
    // (substitution, insertion, deletion, or two neighbours swapped: `lenght`). Close enough
    // to be a typo: at most a third of the name wrong, and never all of it; ties go to the
    // first candidate.
    const size_t n = name.size();
    size_t best_d = 2 * (std::min(std::max<size_t>(1, n / 3), n - 1) + 1);
    auto lower = [](char ch) { return (ch >= 'A' && ch <= 'Z') ? char(ch - 'A' + 'a') : ch; };
    std::vector<size_t> prev2, prev, cur;
    for (const auto& c : candidates) {
        const size_t m = c.size();
        if (2 * (m > n ? m - n : n - m) >= best_d) continue;
        prev2.assign(m + 1, 0);
        prev.resize(m + 1);
        cur.resize(m + 1);
        for (size_t j = 0; j <= m; ++j) prev[j] = 2 * j;
        for (size_t i = 1; i <= n; ++i) {
            cur[0] = 2 * i;
            for (size_t j = 1; j <= m; ++j) {
                const char a = name[i - 1], b = c[j - 1];
                const size_t sub = a == b ? 0 : lower(a) == lower(b) ? 1 : 2;
                cur[j] = std::min({prev[j] + 2, cur[j - 1] + 2, prev[j - 1] + sub});
                if (i > 1 && j > 1 && a == c[j - 2] && name[i - 2] == b) cur[j] = std::min(cur[j], prev2[j - 2] + 2);
            }
            std::swap(prev2, prev);
            std::swap(prev, cur);
        }
        if (prev[m] < best_d) {
            best_d = prev[m];
            best = c;
        }
    }
    return best;
}

}  // namespace sdfc
