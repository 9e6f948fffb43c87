// sdfc: the command line. Each subcommand is a short function over the library stages (the
// render, mesh, bench, preview and watch commands are in their own files, what they share in common.hpp);
// every user error ends as `path:line:col: error:` (scripts, exit 1) or `sdfc: error:` (exit 2 for the
// command line, 1 for anything else).
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>
#include <sstream>

#include <fmt/format.h>

#include "cli/args.hpp"
#include "cli/common.hpp"
#include "cli/options.hpp"
#include "cli/output_checks.hpp"
#include "cli/output_names.hpp"
#include "compiler/bytecode/compile.hpp"
#include "compiler/glsl/glsl.hpp"
#include "compiler/glsl/glsl_tape.hpp"
#include "compiler/scene/lower.hpp"
#include "lang/ast.hpp"
#include "lang/load.hpp"
#include "runtime/io/atomic_file.hpp"
#include "runtime/io/image.hpp"
#include "runtime/cpu/slice.hpp"
#include "runtime/cpu/tracer.hpp"
#include "runtime/eval/isa.hpp"
#include "runtime/eval/vm.hpp"

#ifndef SDFC_VERSION
#define SDFC_VERSION "0.0.0"
#endif

namespace sdfc::cli {

// --format: the image format of standard output (-o -); a file's extension names its own.
std::string image_format_flag(const std::string& out, const std::optional<std::string>& format) {
    if (out == "-") {
        if (!format) throw UsageError("-o - (standard output) needs --format (png, jpg, exr, hdr, tif, ...)");
        std::string f = *format;
        if (!f.empty() && f[0] == '.') f.erase(0, 1);
        return f;
    }
    if (format) throw UsageError(fmt::format("--format is for -o - (standard output); the extension of '{}' names its format", out));
    return "";
}

namespace {

// The flags that override the script's camera and render(...) settings (render and bench).
constexpr const char* kOverrideFlags[] = {"--width",     "--height",  "--samples", "--camera-position", "--camera-target", "--fov",
                                          "--max-steps", "--max-bounces", "--max-distance", "--epsilon", "--shadows", "--ao", "--aa",
                                          "--exposure",  "--tonemap"};

// The render(...) flags of `sdfc glsl`: the shader's knobs and constants (its size is the viewport's).
constexpr const char* kGlslFlags[] = {"--samples", "--max-steps", "--max-bounces", "--max-distance", "--epsilon", "--shadows",
                                      "--ao",      "--aa",        "--exposure",    "--tonemap"};

bool ov_has(const Overrides& ov, const char* flag) {
    for (auto& [k, v] : ov)
        if (k == flag && v) return true;
    return false;
}

Args flat_args(const Overrides& ov) {
    std::vector<std::string> flat;
    for (auto& [k, v] : ov)
        if (v) { flat.push_back(k); flat.push_back(*v); }
    return Args(flat);
}

// The flags of render(...)'s settings, with the script's names and ranges; true when the
// picture's size came from them.
bool apply_render_flags(RenderSettings& r, Args& a) {
    bool sized = false;
    // The limits of render(width=, height=) and of slice.
    if (auto v = a.value("--width")) r.width = Args::to_int("--width", *v, 1, 16384), sized = true;
    if (auto v = a.value("--height")) r.height = Args::to_int("--height", *v, 1, 16384), sized = true;
    if (auto v = a.value("--samples")) r.samples = Args::to_int("--samples", *v, 1, 4096), sized = true;
    if (auto v = a.value("--max-steps")) r.max_steps = Args::to_int("--max-steps", *v, 1, 100000);
    if (auto v = a.value("--max-bounces")) r.max_bounces = Args::to_int("--max-bounces", *v, 0, 64);
    for (auto [flag, field] : {std::pair{"--max-distance", &r.max_distance}, std::pair{"--epsilon", &r.epsilon}})
        if (auto v = a.value(flag)) {
            *field = Args::to_float(flag, *v);
            if (!(*field > 0.0f)) throw UsageError(fmt::format("{} must be above 0, not {}", flag, *v));
            if (field == &r.max_distance) r.max_distance_set = true;
        }
    for (auto [flag, field] : {std::pair{"--shadows", &r.shadows}, std::pair{"--ao", &r.ao}})
        if (auto v = a.value(flag)) {
            if (*v != "on" && *v != "off") throw UsageError(fmt::format("{} takes on or off, not '{}'", flag, *v));
            *field = *v == "on";
        }
    if (auto v = a.value("--exposure")) {
        r.exposure = Args::to_float("--exposure", *v);
        if (!(r.exposure > 0.0f)) throw UsageError(fmt::format("--exposure must be above 0, not {}", *v));
    }
    if (auto v = a.value("--tonemap")) {
        if (*v != "none" && *v != "reinhard" && *v != "aces") throw UsageError(fmt::format("--tonemap takes none, reinhard or aces, not '{}'", *v));
        r.tonemap = *v;
    }
    if (auto v = a.value("--aa")) {
        if (*v != "grid" && *v != "cone") throw UsageError(fmt::format("--aa takes grid or cone, not '{}'", *v));
        r.aa = *v;
    }
    return sized;
}

}  // namespace

static float fov_flag(const std::string& v) {  // (both the early check and apply_overrides)
    const float f = Args::to_float("--fov", v);
    if (!(f > 0 && f < 180)) throw UsageError("--fov must be between 0 and 180 degrees");
    return f;
}

void apply_overrides(CompiledScene& cs, const Overrides& ov, Common& c) {
    Args a = flat_args(ov);
    const bool sized = apply_render_flags(cs.render, a);  // the size comes from flags, not (only) from the script
    if (auto v = a.value("--camera-position")) {
        auto f = Args::to_floats("--camera-position", *v, 3);
        cs.camera.position = {f[0], f[1], f[2]};
    }
    if (auto v = a.value("--camera-target")) {
        auto f = Args::to_floats("--camera-target", *v, 3);
        cs.camera.target = {f[0], f[1], f[2]};
    }
    if (auto v = a.value("--fov")) cs.camera.fov = fov_flag(*v);
    // The flags' camera meets the script's rules (compiler/bytecode/compile.cpp).
    if (ov_has(ov, "--camera-position") || ov_has(ov, "--camera-target")) {
        std::string why = camera_problem(cs.camera);
        if (!why.empty()) throw UsageError("--camera-position/--camera-target: " + why);
    }
    const double rows = std::ceil(double(cs.render.height) / c.bands);  // (a band: about its share)
    if (double(cs.render.width) * rows * cs.render.samples > double(c.max_pixels)) {
        const std::string band = c.bands > 1 ? fmt::format(" ({} rows a band of {})", rows, c.bands) : "";
        std::string msg = fmt::format("{}x{} pixels at {} samples{} is over the limit of {} (raise it with --max-pixels)",
                                      cs.render.width, cs.render.height, cs.render.samples, band, c.max_pixels);
        // The script's render(...) chose the size: point at it.
        if (!sized && cs.render.loc.known()) throw CompileError(cs.render.loc, msg);
        throw UsageError(msg);
    }
}

Overrides read_overrides(Args& a) {
    Overrides ov;
    for (const char* f : kOverrideFlags) ov.emplace_back(f, a.value(f));
    // Their ranges checked now, before a scene is read (watch stops on a bad flag: no save
    // of the scene can fix --width 0); the scene's rules come with apply_overrides.
    RenderSettings dry;
    Args flat = flat_args(ov);
    (void)apply_render_flags(dry, flat);
    for (const char* f : {"--camera-position", "--camera-target"})
        if (auto v = flat.value(f)) (void)Args::to_floats(f, *v, 3);
    if (auto v = flat.value("--fov")) (void)fov_flag(*v);
    return ov;
}

namespace {

int cmd_check(Args& a) {
    Common c = read_common(a);
    c.keep_scene = true;
    std::string path = one_scene(a, "check");
    SourceManager sm;
    try {
        build(sm, path, c, 0.0f);
    } catch (const CompileError& e) {
        // An error only time 0 makes (`1 / time`, `mod(x, time)`): said, as `sdfc glsl`
        // (time left open) takes the script.
        InterpretOptions open = c.interp;
        open.time = std::nullopt;
        try {
            SourceManager again;
            const Scene s = load_scene(again, path, open);
            (void)compile_scene(s);
        } catch (const std::exception&) {
            throw e;
        }
        std::vector<Diagnostic> d = e.diagnostics();
        for (auto& x : d) x.message += " (at time 0, where check reads the script; other times may not fail: render --time T)";
        throw CompileError(std::move(d));
    }
    return 0;
}

int cmd_compile(Args& a) {
    Common c = read_common(a);
    auto emit = a.value("--emit");
    std::string path = one_scene(a, "compile");
    if (!emit) throw UsageError("compile needs --emit ast|ir|bytecode");
    SourceManager sm;
    if (*emit == "ast") {
        if (is_vm_path(path)) throw UsageError("--emit ast needs a .sdf script");
        const SourceFile& f = path == "-" ? sm.load_stdin(c.interp.limits.max_file_bytes) : sm.load(path, Loc{}, c.interp.limits.max_file_bytes);
        auto m = ast::parse(f, ast::ParseOptions{c.interp.limits.max_nesting});
        std::cout << ast::dump(*m);
        interpret_source(sm, f, c.interp);  // report semantic errors too
        return 0;
    }
    if (*emit == "ir") {
        Scene s = load_scene(sm, path, c.interp);
        LoweredScene ls = compile_then_warn(s, [&] { return lower_scene(*s.graph, s); });
        std::vector<NodeId> roots{ls.distance, ls.shading_distance};
        std::vector<std::string> names{"distance", "shading.d"};
        for (int i = 0; i < kMatChannels; ++i) {
            roots.push_back(ls.material[i]);
            names.push_back(std::string("shading.") + kMatChannelInfo[i].output);
        }
        std::cout << dump_ir(*s.graph, roots, names);
        return 0;
    }
    if (*emit == "bytecode") {
        CompiledScene cs = build(sm, path, c, 0.0f);
        std::cout << "; distance program\n" << disassemble(cs.distance) << "\n; shading program\n" << disassemble(cs.shading);
        return 0;
    }
    throw UsageError(fmt::format("--emit takes ast, ir or bytecode, not '{}'", *emit));
}

int cmd_eval(Args& a) {
    Common c = read_common(a);
    auto at = a.value("--at");
    auto points = a.value("--points");
    auto time_s = a.value("--time");
    std::string path = one_scene(a, "eval");
    if (!at && !points) throw UsageError("eval needs --at X,Y,Z or --points FILE");
    if (at && points) throw UsageError("eval takes --at X,Y,Z or --points FILE, not both");
    if (points && *points == "-" && path == "-") throw UsageError("the scene and --points cannot both be standard input (-)");
    std::vector<float> xs, ys, zs;
    if (at) {
        auto f = Args::to_floats("--at", *at, 3);
        xs.push_back(f[0]); ys.push_back(f[1]); zs.push_back(f[2]);
    }
    if (points) read_points(*points, c.interp.limits.max_file_bytes, xs, ys, zs);
    SourceManager sm;
    CompiledScene cs = build(sm, path, c, time_s ? Args::to_float("--time", *time_s) : 0.0f);
    Evaluator ev(cs.distance);
    std::string out;
    for (size_t i = 0; i < xs.size(); i += kBatch) {
        int n = int(std::min<size_t>(kBatch, xs.size() - i));
        ev.eval(&xs[i], &ys[i], &zs[i], n, cs.time);
        for (int j = 0; j < n; ++j) out += fmt::format("{}\n", ev.output(0)[j] + 0.0f);  // + 0: no "-0"
    }
    write_stdout(out);
    return 0;
}

int cmd_slice(Args& a) {
    Common c = read_common(a);
    auto axis = a.value("--axis");
    auto at = a.value("--at");
    auto out = a.value("-o", "--output");
    auto range = a.value("--range");
    auto w = a.value("--width");
    auto h = a.value("--height");
    auto time_s = a.value("--time");
    auto format = a.value("--format");
    std::string path = one_scene(a, "slice");
    if (!out) throw UsageError("slice needs -o OUT");
    const std::string fmt_ext = image_format_flag(*out, format);
    SliceOptions so;
    if (axis) {
        if (*axis != "x" && *axis != "y" && *axis != "z") throw UsageError(fmt::format("--axis takes x, y or z, not '{}'", *axis));
        so.axis = (*axis)[0] - 'x';
    }
    if (at) so.at = Args::to_float("--at", *at);
    if (range) {
        auto f = Args::to_floats("--range", *range, 4);
        so.range = {f[0], f[1], f[2], f[3]};
        if (!(f[1] > f[0]) || !(f[3] > f[2])) throw UsageError("--range needs UMIN < UMAX and VMIN < VMAX");
        for (float v : f)
            if (!(std::fabs(v) <= 1e15f)) throw UsageError("--range must lie within 1e15 of the origin");
    }
    if (w) so.width = Args::to_int("--width", *w, 1, 16384);
    if (h) so.height = Args::to_int("--height", *h, 1, 16384);
    if (range && !h) {  // the height follows the range's shape: within the same limit as --height
        const auto& r = *so.range;
        const double tall = (double(r[3]) - r[2]) / (double(r[1]) - r[0]), rows = so.width * tall;
        if (!(rows <= 16384.5))
            throw UsageError(fmt::format("--range is {:g} times as tall as wide: {:.4g} rows at --width {}, over 16384 (give --height: "
                                         "the picture then shows more of the plane across)",
                                         tall, rows, so.width));
    }
    if (double(so.width) * so.height > double(c.max_pixels))
        throw UsageError(fmt::format("{}x{} pixels is over the limit of {} (raise it with --max-pixels)", so.width, so.height, c.max_pixels));
    check_picture_output(*out, fmt_ext);
    check_not_input(*out, path);
    SourceManager sm;
    CompiledScene cs = build(sm, path, c, time_s ? Args::to_float("--time", *time_s) : 0.0f);
    check_not_input(*out, sm);
    write_image(*out, render_slice(cs, so), WriteOptions{true, fmt_ext});
    return 0;
}

int cmd_glsl(Args& a) {
    Common c = read_common(a);
    auto target = a.value("--target");
    auto out = a.value("-o", "--output");
    auto code = a.value("--code");
    auto tape_file = a.value("--tape-file");
    Overrides ov;
    for (const char* f : kGlslFlags) ov.emplace_back(f, a.value(f));
    std::string path = one_scene(a, "glsl");
    GlslOptions go;
    go.sample = sample_batch;
    if (code) {
        if (*code == "auto") go.code = GlslCode::Auto;
        else if (*code == "straight") go.code = GlslCode::Straight;
        else if (*code == "tape") go.code = GlslCode::Tape;
        else throw UsageError(fmt::format("--code takes auto, straight or tape, not '{}'", *code));
    }
    GlslTarget t = GlslTarget::Shadertoy;
    if (target) {
        if (*target == "shadertoy") t = GlslTarget::Shadertoy;
        else if (*target == "glsl330") t = GlslTarget::Glsl330;
        else if (*target == "html") t = GlslTarget::Html;
        else throw UsageError(fmt::format("--target takes shadertoy, glsl330 or html, not '{}'", *target));
    }
    if (tape_file) {
        if (t != GlslTarget::Glsl330) throw UsageError("--tape-file is for --target glsl330 (Shadertoy cannot load a file; the html page holds its tape)");
        if (go.code == GlslCode::Straight) throw UsageError("--tape-file writes a tape: it does not go with --code straight");
        go.code = GlslCode::Tape;
        go.tape_texture = true;
        resolve_output(*tape_file);
        check_not_input(*tape_file, path);
    }
    if (out) {
        resolve_output(*out);
        check_not_input(*out, path);
    }
    if (tape_file) {
        const bool same = *tape_file == "-" ? !out || *out == "-"
                                            : out && *out != "-" &&
                                                  std::filesystem::weakly_canonical(*out) == std::filesystem::weakly_canonical(*tape_file);
        if (same) throw UsageError(fmt::format("--tape-file and the shader would both go to '{}'", *tape_file));
    }
    SourceManager sm;
    InterpretOptions o = c.interp;
    o.time = std::nullopt;  // `time` becomes iTime
    Scene s = load_scene(sm, path, o);
    if (out) check_not_input(*out, sm);
    if (tape_file) check_not_input(*tape_file, sm);
    Args flags = flat_args(ov);
    apply_render_flags(s.render, flags);
    GlslOutput g = compile_then_warn(s, [&] { return compile_glsl(s, t, go); });
    check_field_finite(s, g.distance, g.probes);
    if (g.tape && g.tape_texels > kNvidiaConstArrayTexels && !go.tape_texture &&
        (t == GlslTarget::Shadertoy || t == GlslTarget::Glsl330))
        std::fprintf(stderr,
                     "sdfc: warning: the scene's tape is one constant array of %zu uvec4s: NVIDIA's GLSL compiler takes at most "
                     "%zu (error C1068: too much data in type constructor); --target html (or glsl330 with --tape-file) keeps "
                     "the tape in a texture\n",
                     g.tape_texels, kNvidiaConstArrayTexels);
    std::string text = std::move(g.text);
    if (tape_file) {  // both or neither; the tape first, before the shader that reads it
        const std::string tape = glsl::tape_bytes(glsl::tape_texture_words(g.tape_words));
        write_files(*tape_file, tape, out ? *out : "-", text);
        return 0;
    }
    if (!out) {
        write_stdout(text);
        return 0;
    }
    write_text_file(*out, text);
    return 0;
}

// `sdfc help [CMD | --man | --completion SHELL]`.
int cmd_help(Args& a) {
    a.declare(option_names(*find_command("help")));
    if (a.flag("--help") || a.flag("-h")) return write_stdout(command_help(*find_command("help"))), 0;
    const bool man = a.flag("--man");
    const auto shell = a.value("--completion");
    const auto what = a.positionals();
    if (man + bool(shell) + !what.empty() > 1) throw UsageError("help takes one of CMD, --man or --completion SHELL");
    if (man) return write_stdout(man_page(SDFC_VERSION)), 0;
    if (shell) {
        const std::string script = completion_script(*shell);
        if (script.empty()) throw UsageError(fmt::format("--completion takes bash or zsh, not '{}'", *shell));
        return write_stdout(script), 0;
    }
    if (what.empty()) return write_stdout(global_help()), 0;
    if (what.size() > 1) throw UsageError(fmt::format("help takes one command, got '{}' too", what[1]));
    const CommandSpec* c = find_command(what[0]);
    if (!c) throw UsageError(fmt::format("help: no command '{}' (see sdfc --help)", what[0]));
    return write_stdout(command_help(*c)), 0;
}

int run_command(const std::vector<std::string>& all);

int dispatch(const std::vector<std::string>& all) {
    if (all.empty()) {
        std::fputs(global_help().c_str(), stderr);
        return 2;
    }
    if (all[0] == "--help" || all[0] == "-h") return write_stdout(global_help()), 0;
    if (all[0] == "--version") {
        // The batch kernels in use (runtime/eval/isa.hpp; SDFC_ISA=baseline|avx2|avx512 caps them).
        std::printf("sdfc %s (kernels: %s)\n", SDFC_VERSION, isa_name(current_isa()));
        return 0;
    }
    std::string cmd = all[0];
    if (cmd == "watch") return cmd_watch(std::vector<std::string>(all.begin() + 1, all.end()), run_command);
    Args a(std::vector<std::string>(all.begin() + 1, all.end()));
    if (cmd == "help") return cmd_help(a);
    if (const CommandSpec* spec = find_command(cmd)) {
        a.declare(option_names(*spec));
        if (a.flag("--help") || a.flag("-h")) return write_stdout(command_help(*spec)), 0;
    }
    if (cmd == "render") return cmd_render(a);
    if (cmd == "check") return cmd_check(a);
    if (cmd == "compile") return cmd_compile(a);
    if (cmd == "eval") return cmd_eval(a);
    if (cmd == "slice") return cmd_slice(a);
    if (cmd == "glsl") return cmd_glsl(a);
    if (cmd == "bench") return cmd_bench(a);
    if (cmd == "mesh") return cmd_mesh(a);
    if (cmd == "preview") return cmd_preview(a);
    if (cmd == "merge") return cmd_merge(a);
    std::vector<std::string> cmds;
    for (const CommandSpec& c : commands()) cmds.push_back(c.name);
    if (cmd.rfind("--", 0) == 0) cmds = {"--help", "--version"};  // (the options before a command)
    std::string near = nearest_name(cmd, cmds);
    throw UsageError(near.empty() ? fmt::format("unknown command '{}' (see sdfc --help)", cmd)
                                  : fmt::format("unknown command '{}' (did you mean `{}`?)", cmd, near));
}

// A command, its errors reported as main reports them (sdfc watch runs commands this way).
int run_command(const std::vector<std::string>& all) {
    try {
        return dispatch(all);
    } catch (const sdfc::CompileError& e) {
        std::string s = e.formatted();
        std::fwrite(s.data(), 1, s.size(), stderr);
        return 1;
    } catch (const sdfc::cli::UsageError& e) {  // the command line, not the script: exit 2
        std::fprintf(stderr, "sdfc: error: %s\n", e.what());
        return 2;
    } catch (const sdfc::DefineError& e) {  // a -D the script cannot take: the command line too
        std::fprintf(stderr, "sdfc: error: %s\n", e.what());
        return 2;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "sdfc: error: out of memory: the work is too big for this machine (a smaller picture, fewer samples, "
                             "or lower --max-* limits)\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sdfc: error: %s\n", e.what());
        return 1;
    }
}

}  // namespace
}  // namespace sdfc::cli

namespace {

int run(int argc, char** argv) { return sdfc::cli::run_command(std::vector<std::string>(argv + 1, argv + argc)); }

// Whatever a command printed must have reached standard output (a full disk, a closed
// pipe end): flushed and checked here, and closed and checked at exit.
int finish_stdout(int rc) {
    errno = 0;
    std::cout.flush();
    const bool bad = !std::cout.good() || std::fflush(stdout) != 0 || std::ferror(stdout);
    if (bad) {
        sdfc::cli::report_stdout_error(errno);
        return 1;
    }
    return rc;
}

}  // namespace

// The command runs on a thread with a big stack: the interpreter and the compiler recurse
// once per level of a deep (legal) script, and the main thread's 8 MB can run out before
// the limits do, especially with raised limits or under sanitizers. 1 GiB of address space,
// touched only as deep as the script goes; the stack guard (compiler/base/source.hpp) still stops
// anything deeper with a located error.
int main(int argc, char** argv) {
    int rc = 1;
    const size_t stack = std::min(sdfc::max_thread_stack(), size_t(1) << 30);
    sdfc::install_temp_cleanup();
    // A closed pipe is a write error to report (exit 1), not a signal that kills silently.
    ::signal(SIGPIPE, SIG_IGN);
    auto work = [&] {
        sdfc::cli::use_big_pages();  // (the heap of the thread that parses and compiles)
        rc = finish_stdout(run(argc, argv));
    };
    if (!sdfc::run_on_new_stack(stack, work)) work();
    errno = 0;
    // (EBADF: standard output was closed, and nothing went to it, or the flush above would
    // have failed: not an error, as for GNU tools)
    if (std::fclose(stdout) != 0 && errno != EBADF) {
        sdfc::cli::report_stdout_error(errno);
        return 1;
    }
    return rc;
}
