#include "cli/common.hpp"

#include <cctype>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include <fmt/format.h>

#include "cli/output_checks.hpp"
#include "lang/load.hpp"

namespace sdfc::cli {

Common read_common(Args& a) {
    Common c;
    Limits& l = c.interp.limits;
    if (auto v = a.value("--max-recursion")) l.max_recursion = Args::to_int("--max-recursion", *v, 1, 100000);
    if (auto v = a.value("--max-iterations")) {
        l.max_loop_iterations = Args::to_int("--max-iterations", *v, 1, 2000000000);
        l.max_total_iterations = std::max<long>(l.max_total_iterations, l.max_loop_iterations * 100L);
    }
    if (auto v = a.value("--max-calls")) l.max_calls = size_t(Args::to_int("--max-calls", *v, 1, 2000000000));
    if (auto v = a.value("--max-shapes")) l.max_shapes = size_t(Args::to_int("--max-shapes", *v, 1, 2000000000));
    if (auto v = a.value("--max-shape-depth")) l.max_shape_depth = Args::to_int("--max-shape-depth", *v, 1, 10000);
    if (auto v = a.value("--max-ops")) l.max_ops = size_t(Args::to_int("--max-ops", *v, 1, 2000000000));
    if (auto v = a.value("--max-file-size")) l.max_file_bytes = size_t(Args::to_int("--max-file-size", *v, 1, 2000000000));
    if (auto v = a.value("--max-nesting")) l.max_nesting = Args::to_int("--max-nesting", *v, 1, 10000);
    if (auto v = a.value("--max-pixels")) c.max_pixels = Args::to_int("--max-pixels", *v, 1, 2000000000);
    if (auto v = a.value("--max-frames")) c.max_frames = Args::to_int("--max-frames", *v, 1, 100000000);
    // -D name=value (OpenSCAD's flag): the script's top-level `let name` takes the value.
    for (const std::string& d : a.values("-D")) {
        const size_t eq = d.find('=');
        const std::string name = d.substr(0, eq);
        bool ident = !name.empty() && !std::isdigit(static_cast<unsigned char>(name[0]));
        for (char ch : name) ident &= std::isalnum(static_cast<unsigned char>(ch)) || ch == '_';
        if (eq == std::string::npos || !ident || eq + 1 == d.size())
            throw UsageError(fmt::format("-D takes NAME=VALUE (a top-level let of the script and an expression), not '{}'", d));
        for (const Define& seen : c.interp.defines)
            if (seen.name == name) throw UsageError(fmt::format("-D {} is given twice", name));
        c.interp.defines.push_back({name, d.substr(eq + 1)});
    }
    return c;
}

std::string one_scene(Args& a, const char* cmd) {
    auto pos = a.positionals();
    if (pos.empty()) throw UsageError(fmt::format("{} needs a scene file", cmd));
    if (pos.size() > 1) throw UsageError(fmt::format("{} takes one scene file, got '{}' too", cmd, pos[1]));
    return pos[0];
}

CompiledScene build(SourceManager& sm, const std::string& path, Common& c, std::optional<float> time) {
    InterpretOptions o = c.interp;
    o.time = time;
    Scene s = load_scene(sm, path, o);
    CompiledScene cs = compile_scene(s);
    check_field_finite(s, cs);
    return cs;
}

// More threads than the machine runs at once only add overhead (and TBB warns past its
// limit): the request is capped there.
int thread_count(const std::string& v) {
    int n = Args::to_int("--threads", v, 1, 1024);
    unsigned hw = std::thread::hardware_concurrency();
    return hw > 0 ? std::min<int>(n, int(hw)) : n;
}

double progress_after_s() {
    const char* v = std::getenv("SDFC_PROGRESS_AFTER");
    return v && *v ? std::atof(v) : 1.0;
}

void progress_line(const std::string& target, double frac, double elapsed_s, double eta, const std::string& label) {
    const int width = 30, fill = std::clamp(int(frac * width), 0, width);
    std::fprintf(stderr, "\r\033[Ksdfc: %s [%s%s] %3d%%%s%s  %.1f s", target.c_str(), std::string(size_t(fill), '#').c_str(),
                 std::string(size_t(width - fill), '.').c_str(), int(frac * 100.0), label.empty() ? "" : " ", label.c_str(), elapsed_s);
    if (eta >= 0.0) std::fprintf(stderr, ", ETA %.1f s", eta);
}

}  // namespace sdfc::cli
