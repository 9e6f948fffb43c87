// compiler/render/rules.h turned into GLSL (see glsl_renderer.hpp): the one text of the
// per-ray rules, in the shader.
#include <regex>

#include "compiler/glsl/glsl_renderer.hpp"

namespace sdfc::glsl {

namespace {
std::string to_glsl(std::string code) {
    static const std::regex fn(R"(SDF_FN )"), inout(R"(SDF_INOUT\((\w+)\))"), outp(R"(SDF_OUT\((\w+)\))");
    static const std::regex and_(R"(\bSDF_AND\b)"), or_(R"(\bSDF_OR\b)");
    if (code.find("SDF_") == std::string::npos) return code;
    code = std::regex_replace(code, fn, "");
    code = std::regex_replace(code, and_, "&&");
    code = std::regex_replace(code, or_, "||");
    code = std::regex_replace(code, inout, "inout $1");
    return std::regex_replace(code, outp, "out $1");
}
}  // namespace

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
        // The macros become GLSL in the code, not in the comments that name them.
        const size_t comment = line.find("//");
        out.append(to_glsl(std::string(line.substr(0, comment))));
        if (comment != std::string_view::npos) out.append(line.substr(comment));
        out.push_back('\n');
    }
    // Leading blank lines (after the C++ prelude) go.
    const size_t first = out.find_first_not_of('\n');
    return first == std::string::npos ? std::string() : out.substr(first);
}

}  // namespace sdfc::glsl
