// compiler/render/rules.h turned into GLSL (see glsl_renderer.hpp): the one text of the
// per-ray rules, in the shader.
#include <regex>

#include "compiler/glsl/glsl_renderer.hpp"

namespace sdfc::glsl {

std::string shared_rules_glsl(std::string_view rules_h) {
    std::string out;
    bool cxx_only = false;
    size_t begin = 0;
    while (begin < rules_h.size()) {
        size_t end = rules_h.find('\n', begin);
        if (end == std::string_view::npos) end = rules_h.size();
        const std::string_view line = rules_h.substr(begin, end - begin);
        begin = end + 1;
        if (line.rfind("#ifdef __cplusplus", 0) == 0) {
            cxx_only = true;
            continue;
        }
        if (cxx_only) {
            if (line.rfind("#endif", 0) == 0) cxx_only = false;
            continue;
        }
        out.append(line);
        out.push_back('\n');
    }
    static const std::regex fn(R"(SDF_FN )"), inout(R"(SDF_INOUT\((\w+)\))"), outp(R"(SDF_OUT\((\w+)\))");
    static const std::regex and_(R"(\bSDF_AND\b)"), or_(R"(\bSDF_OR\b)");
    out = std::regex_replace(out, fn, "");
    out = std::regex_replace(out, and_, "&&");
    out = std::regex_replace(out, or_, "||");
    out = std::regex_replace(out, inout, "inout $1");
    out = std::regex_replace(out, outp, "out $1");
    // Leading blank lines (after the C++ prelude) go.
    const size_t first = out.find_first_not_of('\n');
    return first == std::string::npos ? std::string() : out.substr(first);
}

}  // namespace sdfc::glsl
