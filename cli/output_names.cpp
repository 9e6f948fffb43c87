#include "cli/output_names.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <unordered_map>

#include <fmt/format.h>

#include "cli/args.hpp"
#include "cli/output_checks.hpp"
#include "runtime/io/image.hpp"

namespace sdfc::cli {

std::string scene_name(const std::string& path) { return path == "-" ? "stdin" : std::filesystem::path(path).stem().string(); }

std::string expand(const std::string& out, int frame, const std::string& name) {
    std::string r;
    for (size_t i = 0; i < out.size(); ++i) {
        const char ch = out[i];
        if ((ch == '{' || ch == '}') && i + 1 < out.size() && out[i + 1] == ch) {
            r += ch;
            ++i;
            continue;
        }
        if (ch == '}')
            throw UsageError(fmt::format("the output name '{}' has a '}}' with no '{{' (write }}}} for a brace)", out));
        if (ch != '{') {
            r += ch;
            continue;
        }
        const size_t e = out.find('}', i);
        if (e == std::string::npos)
            throw UsageError(fmt::format("the output name '{}' has a '{{' with no '}}' (known: {{frame:04d}}, {{frame}}, {{name}})", out));
        const std::string key = out.substr(i + 1, e - i - 1);
        if (key == "frame") {
            r += std::to_string(frame);
        } else if (key == "name") {
            r += name;
        } else if (key.rfind("frame:", 0) == 0) {
            const std::string spec = key.substr(6);
            const std::string digits = spec.empty() ? spec : spec.substr(0, spec.size() - 1);
            if (spec.empty() || spec.back() != 'd' || digits.find_first_not_of("0123456789") != std::string::npos)
                throw UsageError(fmt::format("unsupported frame format '{{frame:{}}}' (use {{frame:04d}})", spec));
            const size_t lead = std::min(digits.find_first_not_of('0'), digits.size());  // 010d: width 10
            const int width = digits.size() - lead > 2 ? 99 : std::atoi(digits.c_str() + lead);
            if (width > 32)
                throw UsageError(fmt::format("unsupported frame format '{{frame:{}}}' (at most 32 digits)", spec));
            r += fmt::format("{:0{}d}", frame, width);
        } else {
            throw UsageError(fmt::format("unknown '{{{}}}' in the output name '{}' (known: {{frame:04d}}, {{frame}}, {{name}}; "
                                         "write {{{{ and }}}} for braces)",
                                         key, out));
        }
        i = e;
    }
    return r;
}

void check_distinct_outputs(const std::string& out, const std::vector<std::string>& scenes, int f0, int f1,
                            const std::vector<std::string>& side_aovs) {
    struct Written {
        size_t scene;
        int frame;
        std::string aov;  // empty: the picture, else its side file
    };
    std::unordered_map<std::string, Written> seen;
    auto what = [&](const Written& w) {
        std::string s = w.aov.empty() ? "" : fmt::format("the {} side file of ", w.aov);
        s += fmt::format("'{}'", scenes[w.scene]);
        if (f1 > f0) s += fmt::format(" frame {}", w.frame);
        return s;
    };
    auto note = [&](const std::string& path, const Written& w) {
        const auto [it, fresh] = seen.emplace(path, w);
        if (fresh) return;
        const Written& v = it->second;
        if (v.scene == w.scene && v.aov.empty() && w.aov.empty())
            throw UsageError(fmt::format("frames {} and {} would both be written to '{}'", v.frame, w.frame, path));
        if (v.aov.empty() && w.aov.empty())
            throw UsageError(fmt::format("'{}' and '{}' would both be written to '{}' ({{name}} is the file name without its "
                                         "folder and extension)",
                                         scenes[v.scene], scenes[w.scene], path));
        throw UsageError(fmt::format("{} and {} would both be written to '{}'", what(v), what(w), path));
    };
    for (size_t i = 0; i < scenes.size(); ++i)
        for (int f = f0; f <= f1; ++f) {
            const std::string target = expand(out, f, scene_name(scenes[i]));
            note(target, Written{i, f, ""});
            if (target != "-" && !is_exr(target))
                for (const std::string& a : side_aovs) note(aov_side_path(target, a), Written{i, f, a});
        }
}

}  // namespace sdfc::cli
