#include "cli/common.hpp"

#include <cctype>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <set>
#include <sstream>
#include <string_view>
#include <thread>
#include <utility>

#include <fmt/format.h>

#include "cli/output_checks.hpp"
#include "lang/ast.hpp"
#include "lang/load.hpp"
#include "runtime/eval/vm.hpp"

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
    if (auto v = a.value("--max-list")) l.max_list = size_t(Args::to_int("--max-list", *v, 1, 2000000000));
    if (auto v = a.value("--max-shape-depth")) l.max_shape_depth = Args::to_int("--max-shape-depth", *v, 1, 10000);
    if (auto v = a.value("--max-ops")) l.max_ops = size_t(Args::to_int("--max-ops", *v, 1, 2000000000));
    if (auto v = a.value("--max-file-size")) l.max_file_bytes = size_t(Args::to_int("--max-file-size", *v, 1, 2000000000));
    if (auto v = a.value("--max-nesting")) l.max_nesting = Args::to_int("--max-nesting", *v, 1, sdfc::ast::ParseOptions::kMostNesting);
    if (auto v = a.value("--max-pixels")) c.max_pixels = Args::to_int("--max-pixels", *v, 1, 2000000000);
    if (auto v = a.value("--max-frames")) c.max_frames = Args::to_int("--max-frames", *v, 1, 100000000);
    // -D name=value (OpenSCAD's flag): the script's top-level `let name` takes the value.
    for (const std::string& d : a.values("-D")) {
        const size_t eq = d.find('=');
        // (OpenSCAD's -D takes spaces around the '=': -D 'x = 2')
        std::string name = d.substr(0, eq);
        while (!name.empty() && (name.back() == ' ' || name.back() == '\t')) name.pop_back();
        while (!name.empty() && (name.front() == ' ' || name.front() == '\t')) name.erase(0, 1);
        bool ident = !name.empty() && !std::isdigit(static_cast<unsigned char>(name[0]));
        for (char ch : name) ident &= std::isalnum(static_cast<unsigned char>(ch)) || ch == '_';
        if (eq == std::string::npos || !ident || eq + 1 == d.size())
            throw UsageError(fmt::format("-D takes NAME=VALUE (a top-level let of the script and an expression), not '{}'", d));
        for (const Define& seen : c.interp.defines)
            if (seen.name == name) throw UsageError(fmt::format("-D {} is given twice", name));
        try {  // (a message would quote the bytes as they are)
            check_source_text(SourceFile("-D", d.substr(eq + 1)));
        } catch (const CompileError&) {
            throw UsageError(fmt::format("-D {}: the value is not text (a NUL byte or invalid UTF-8)", name));
        }
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

namespace {
std::set<std::string> g_warned;  // each warning once (a scene compiles once per frame)

// With Common::keep_scene, the last build's Scene is kept until the next build or the
// process's end: its teardown (the interpreter's state, the syntax tree, the shapes) is work
// the exit makes moot, 8 % of a 10,000-statement check. Freed before the next build, so
// watch's rebuilds never hold two. Reachable from here, so leak checkers do not count it.
// Not for commands that render: they would hold it through the render.
std::mutex g_kept_mutex;
Scene* g_kept = nullptr;

void keep_until_next_build(Scene&& s) {
    std::lock_guard<std::mutex> lock(g_kept_mutex);
    delete g_kept;
    g_kept = new Scene(std::move(s));
}

void free_kept_scene() {
    std::lock_guard<std::mutex> lock(g_kept_mutex);
    delete std::exchange(g_kept, nullptr);
}
}  // namespace

void print_warnings(const Scene& s) { print_warnings(s, nullptr); }

void print_warnings(const Scene& s, const CompileError* besides) {
    for (const Diagnostic& w : s.warnings) {
        if (besides && std::any_of(besides->diagnostics().begin(), besides->diagnostics().end(), [&](const Diagnostic& d) {
                return d.loc.file == w.loc.file && d.loc.line == w.loc.line && d.loc.col == w.loc.col;
            }))
            continue;
        const std::string text = format_diagnostic(w, "warning");
        if (g_warned.insert(text).second) std::fwrite(text.data(), 1, text.size(), stderr);
    }
}

void forget_warnings() { g_warned.clear(); }

CompiledScene build(SourceManager& sm, const std::string& path, Common& c, std::optional<float> time) {
    InterpretOptions o = c.interp;
    o.time = time;
    free_kept_scene();
    Scene s = load_scene(sm, path, o);
    CompiledScene cs = compile_then_warn(s, [&] { return compile_scene(s); });
    check_field_finite(s, cs);
    if (c.keep_scene) keep_until_next_build(std::move(s));
    return cs;
}

std::string view_problem(const CompiledScene& cs) {
    if (cs.is_2d || cs.raw_field || cs.distance.outputs.empty()) return "";
    const Bounds& b = cs.bounds.finite() ? cs.bounds : cs.solid_bounds;
    const ResolvedCamera& cam = cs.camera;
    const glm::vec3 c = cam.position;
    auto inside = [&] {
        float d = 0.0f;
        sample_batch(cs.distance, &c.x, &c.y, &c.z, 1, cs.time, &d);
        return d < 0.0f ? fmt::format("the camera (at {}, {}, {}) is inside the scene's solid: the picture shows it from within", c.x, c.y, c.z)
                        : std::string();
    };
    // (unbounded: a repeat, a custom field, a floor the camera is under)
    if (!b.finite() || !(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) return inside();
    if (glm::all(glm::greaterThanEqual(c, b.lo)) && glm::all(glm::lessThanEqual(c, b.hi))) return inside();
    if (out_of_view(cam, b.lo, b.hi, float(cs.render.width) / float(std::max(cs.render.height, 1))))
        return fmt::format("nothing of the scene is in view: the camera at {}, {}, {} looks at {}, {}, {}, away from the scene's bounds "
                           "[{}, {}, {}] .. [{}, {}, {}]",
                           c.x, c.y, c.z, cam.target.x, cam.target.y, cam.target.z, b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z);
    return "";
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

void read_points(const std::string& path, size_t max_bytes, std::vector<float>& xs, std::vector<float>& ys, std::vector<float>& zs) {
    // A bad line is an error in an input file: path:line:col, the line and a caret, exit 1.
    const SourceFile file(path == "-" ? "<stdin>" : path, read_bounded(path, max_bytes));  // (-: standard input)
    // "x y z", or "x,y,z" as --at takes it (a CSV file); a byte-order mark first is skipped.
    for (uint32_t ln = 1; ln <= file.line_starts.size(); ++ln) {
        const std::string_view line = file.line(ln);
        float v[3];
        size_t pos = ln == 1 && line.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;
        int k = 0;
        for (;; ++k) {
            pos = line.find_first_not_of(k > 0 ? " \t\r," : " \t\r", pos);
            if (pos == std::string_view::npos) break;
            const size_t end = std::min(line.find_first_of(" \t\r,", pos), line.size());
            std::istringstream ts{std::string(line.substr(pos, end - pos))};
            float f = 0.0f;
            if (k == 3 || !(ts >> f) || ts.peek() != std::char_traits<char>::eof())
                throw CompileError(Loc{&file, ln, uint32_t(pos + 1)}, k == 3 ? "expected three numbers \"x y z\", not more"
                                                                             : "expected three numbers \"x y z\"");
            v[k] = f;
            pos = end;
        }
        if (k == 0) continue;  // a blank line
        if (k < 3) throw CompileError(Loc{&file, ln, uint32_t(line.size() + 1)}, "expected three numbers \"x y z\"");
        xs.push_back(v[0]); ys.push_back(v[1]); zs.push_back(v[2]);
    }
}

void check_2d_render(const std::string& scene, const Overrides& ov, const PictureAsks& asks, bool warn) {
    const char* flag = asks.tiles ? "--tiles" : asks.aovs ? "--aov" : asks.alpha ? "--alpha on" : asks.steps ? "--view steps" : nullptr;
    if (flag)
        throw UsageError(fmt::format("{}: '{}' is a 2D model, rendered whole as its sign image (white inside, black outside): "
                                     "no bands, AOVs, alpha or step view",
                                     flag, scene));
    std::string unused;
    for (const auto& [k, v] : ov)
        if (v && k != "--width" && k != "--height") unused += (unused.empty() ? "" : ", ") + k;
    if (warn && !unused.empty())
        std::fprintf(stderr, "sdfc: warning: '%s' is a 2D model, rendered as its sign image: %s change nothing\n", scene.c_str(),
                     unused.c_str());
}

}  // namespace sdfc::cli
