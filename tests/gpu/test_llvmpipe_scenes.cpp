// CPU renderer against the GLSL renderer (llvmpipe) on scenes as a new user writes them
// (tests/gpu/scenes: glass and mirror bounces, recursive defs and fields, a crowd of 144
// shapes, soft shadows + AO + cone AA) and on every example, each at the script's own
// samples per pixel (not one, as test_llvmpipe.cpp draws them), at 160x90. The project's
// target is PSNR >= 45 dB; the PSNR of each is printed, and DRIFT.md says where the two
// renderers differ and why.
//
// The hidden test "[.drift]" is the tool behind DRIFT.md: it draws one scene both ways and
// writes STEM.cpu.png, STEM.llvmpipe.png and STEM.diff.png (|difference| x 8) to
// SDFC_GPU_OUT (else a temp folder). Environment:
//   SDFC_DRIFT_SCENE  the scene (.sdf or .vm)
//   SDFC_DRIFT_SIZE   WxH (default 320x180)
//   SDFC_DRIFT_SET    render settings for both renderers, e.g. "shadows=0,ao=0,max_bounces=0"
//                     (shadows ao samples max_bounces max_steps max_distance epsilon aa)
//   SDFC_DRIFT_CPU    "baseline": the CPU renders with --baseline (no tape tree, no
//                     over-relaxation, no clipping, no tile pre-march)
//   SDFC_DRIFT_CODE   straight, tape (the html page's shader, its tape in a texture) or
//                     const-tape (Shadertoy's, the tape in a constant array)
//   SDFC_DRIFT_GLSL_SUB  "FROM=>TO;...": text replaced in the shader (first occurrence), e.g.
//                     "SDF_RELAX = 1.5=>SDF_RELAX = 1.0"
// Run: SDFC_DRIFT_SCENE=tests/gpu/scenes/crowd.sdf build/tests/test_gpu_llvmpipe '[.drift]'
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "shadertoy.hpp"

namespace {

using namespace sdfc;
using namespace sdfc::gpu_test;

constexpr int kWidth = 160, kHeight = 90;
constexpr double kTargetPsnr = 45.0;

std::vector<std::string> scenes(const std::string& sub = "") {
    std::vector<std::string> out;
    const fs::path dir = fs::path(SDFC_SOURCE_DIR) / "tests" / "gpu" / "scenes" / sub;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.is_regular_file() && e.path().extension() == ".sdf") out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

// "shadows=0,ao=0,max_bounces=1" applied to `rs` (unknown names are an error).
void apply_settings(RenderSettings& rs, const std::string& spec) {
    std::stringstream in(spec);
    std::string item;
    while (std::getline(in, item, ',')) {
        if (item.empty()) continue;
        const size_t eq = item.find('=');
        if (eq == std::string::npos) throw std::runtime_error("SDFC_DRIFT_SET: no '=' in '" + item + "'");
        const std::string k = item.substr(0, eq), v = item.substr(eq + 1);
        if (k == "shadows") rs.shadows = v != "0" && v != "false";
        else if (k == "ao") rs.ao = v != "0" && v != "false";
        else if (k == "samples") rs.samples = std::stoi(v);
        else if (k == "max_bounces") rs.max_bounces = std::stoi(v);
        else if (k == "max_steps") rs.max_steps = std::stoi(v);
        else if (k == "max_distance") rs.max_distance = std::stof(v);
        else if (k == "epsilon") rs.epsilon = std::stof(v);
        else if (k == "aa") rs.aa = v;
        else throw std::runtime_error("SDFC_DRIFT_SET: unknown setting '" + k + "'");
    }
}

struct Pair {
    Rgb8 cpu, gpu;
    double cpu_ms = 0, gpu_ms = 0;
    int samples = 1;
};

// `path` at width x height, at the script's samples (changed by `settings`), on both renderers.
// `code`: how the shader holds the programs; Tape draws the html page's shader (the tape
// in a texture) unless `const_tape`, which draws the Shadertoy one (the tape in a constant array).
Pair render_both(Gles& gles, const std::string& path, int width, int height, const std::string& settings = "",
                 bool cpu_baseline = false, GlslCode code = GlslCode::Auto, bool const_tape = false) {
    Pair out;
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    {
        SourceManager sm;
        Scene s = load_scene(sm, path, InterpretOptions{});
        apply_settings(s.render, settings);
        CompiledScene cs = compile_scene(s);
        cs.render.width = width;
        cs.render.height = height;
        out.samples = cs.render.aa == "cone" ? 1 : cs.render.samples;
        RenderOptions ro;
        ro.baseline = cpu_baseline;
        out.cpu = to_rgb8(render(cs, ro));
    }
    const auto t1 = clock::now();
    std::string glsl;
    {
        SourceManager sm;
        InterpretOptions o;
        o.time = std::nullopt;
        Scene s = load_scene(sm, path, o);
        apply_settings(s.render, settings);
        GlslOptions go;
        go.code = code;
        if (code == GlslCode::Tape && !const_tape) {
            const GlslOutput html = compile_glsl(s, GlslTarget::HtmlShader, go);
            const std::string err = draw_html_shader(gles, html, width, height, out.gpu);
            if (!err.empty()) throw std::runtime_error(path + ": " + err);
            out.cpu_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
            out.gpu_ms = std::chrono::duration<double, std::milli>(clock::now() - t1).count();
            return out;
        }
        glsl = compile_glsl(s, GlslTarget::Shadertoy, go).text;
    }
    if (const char* sub = std::getenv("SDFC_DRIFT_GLSL_SUB")) {  // "FROM=>TO;FROM=>TO": edits of the shader
        std::stringstream in(sub);
        std::string item;
        while (std::getline(in, item, ';')) {
            const size_t arrow = item.find("=>");
            if (arrow == std::string::npos) continue;
            const std::string from = item.substr(0, arrow), to = item.substr(arrow + 2);
            const size_t at = glsl.find(from);
            if (at == std::string::npos) throw std::runtime_error("SDFC_DRIFT_GLSL_SUB: '" + from + "' is not in the shader");
            glsl.replace(at, from.size(), to);
        }
    }
    const std::string err = draw_shadertoy(gles, shadertoy_wrap(glsl), width, height, out.gpu);
    if (!err.empty()) throw std::runtime_error(path + ": " + err);
    const auto t2 = clock::now();
    out.cpu_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    out.gpu_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
    return out;
}

// |a - b| x 8 per channel: where the renderers disagree, bright.
Rgb8 diff_image(const Rgb8& a, const Rgb8& b) {
    Rgb8 d{a.width, a.height, std::vector<uint8_t>(a.px.size())};
    for (size_t i = 0; i < a.px.size(); ++i) d.px[i] = static_cast<uint8_t>(std::min(255, 8 * std::abs(int(a.px[i]) - int(b.px[i]))));
    return d;
}

// Share of pixels that differ by more than 8 (of 255) in some channel.
double bad_pixels(const Rgb8& a, const Rgb8& b) {
    size_t bad = 0, n = a.px.size() / 3;
    for (size_t p = 0; p < n; ++p) {
        int m = 0;
        for (int c = 0; c < 3; ++c) m = std::max(m, std::abs(int(a.px[p * 3 + c]) - int(b.px[p * 3 + c])));
        bad += m > 8;
    }
    return n ? static_cast<double>(bad) / static_cast<double>(n) : 0.0;
}

void save_pair(const Pair& p, const std::string& stem) {
    const fs::path out = out_dir();
    save(p.cpu, out / (stem + ".cpu.png"));
    save(p.gpu, out / (stem + ".llvmpipe.png"));
    save(diff_image(p.cpu, p.gpu), out / (stem + ".diff.png"));
}

// Draws each of `files` both ways and checks PSNR >= kTargetPsnr.
void check_all(Gles& gles, const std::vector<std::string>& files, GlslCode code = GlslCode::Auto, bool const_tape = false,
               int width = kWidth, int height = kHeight) {
    double lowest = INFINITY;
    std::string lowest_name;
    for (const std::string& path : files) {
        const std::string name = fs::path(path).stem().string();
        INFO("scene " << path);
        const Pair p = render_both(gles, path, width, height, "", false, code, const_tape);
        const double db = psnr(p.cpu, p.gpu);
        std::printf("  %-24s PSNR %7.2f dB  %5.2f%% pixels off by > 8  (samples %d; cpu %5.0f ms, llvmpipe %6.0f ms)\n", name.c_str(),
                    db, 100.0 * bad_pixels(p.cpu, p.gpu), p.samples, p.cpu_ms, p.gpu_ms);
        std::fflush(stdout);
        if (db < lowest) lowest = db, lowest_name = name;
        if (db < kTargetPsnr || std::getenv("SDFC_GPU_OUT")) save_pair(p, name + (code == GlslCode::Tape ? ".tape" : ""));
        CHECK(db >= kTargetPsnr);
    }
    std::printf("lowest PSNR: %.2f dB (%s) over %zu scenes at %dx%d\n", lowest, lowest_name.c_str(), files.size(), width, height);
}

bool start(Gles& gles) {
    const std::string why = gles.init();
    if (!why.empty()) {
        WARN("SKIPPED: no headless GLES 3 through EGL/llvmpipe here: " << why);
        return false;
    }
    if (gles.renderer().find("llvmpipe") == std::string::npos) WARN("the GLES renderer is '" << gles.renderer() << "', not llvmpipe");
    return true;
}

}  // namespace

TEST_CASE("scenes a new user writes match between the CPU and llvmpipe at their own samples", "[gpu][llvmpipe][scenes]") {
    Gles gles;
    if (!start(gles)) return;
    const auto files = scenes();
    REQUIRE(files.size() >= 4);
    check_all(gles, files);
}

TEST_CASE("every example matches between the CPU and llvmpipe at its own samples", "[gpu][llvmpipe][scenes]") {
    Gles gles;
    if (!start(gles)) return;
    const auto files = examples();
    REQUIRE_FALSE(files.empty());
    check_all(gles, files);
}

// The tape interpreter (compiler/glsl/glsl_tape.hpp), which big scenes get (tests/gpu/scenes/big:
// 2,047 boxes in a tree, 10,000 spheres: guards skip most of them): the html page's shader
// with its tape in a texture, and the Shadertoy one with it in a constant array. Small
// pictures: llvmpipe runs an interpreter's switch under lane masks, every case each turn.
TEST_CASE("every example and big scene matches through the tape interpreter", "[gpu][llvmpipe][scenes][tape]") {
    Gles gles;
    if (!start(gles)) return;
    std::vector<std::string> files = examples();
    for (const std::string& f : scenes("big")) files.push_back(f);
    std::printf("the html page's shader (tape texture):\n");
    check_all(gles, files, GlslCode::Tape, false, 64, 36);
    std::printf("Shadertoy's (constant array):\n");
    check_all(gles, {files.front()}, GlslCode::Tape, true, 64, 36);
}

TEST_CASE("drift tool: one scene both ways, with pictures (SDFC_DRIFT_SCENE)", "[.drift]") {
    const char* scene = std::getenv("SDFC_DRIFT_SCENE");
    if (!scene || !*scene) {
        WARN("set SDFC_DRIFT_SCENE");
        return;
    }
    int w = 320, h = 180;
    if (const char* s = std::getenv("SDFC_DRIFT_SIZE")) std::sscanf(s, "%dx%d", &w, &h);
    const char* set = std::getenv("SDFC_DRIFT_SET");
    const char* cpu_env = std::getenv("SDFC_DRIFT_CPU");
    const bool baseline = cpu_env && std::string(cpu_env) == "baseline";
    Gles gles;
    if (!start(gles)) return;
    const char* code_env = std::getenv("SDFC_DRIFT_CODE");  // straight, tape (the html shader) or const-tape (Shadertoy's)
    const std::string code = code_env ? code_env : "";
    const Pair p = render_both(gles, scene, w, h, set ? set : "", baseline,
                               code == "straight" ? GlslCode::Straight : code.empty() ? GlslCode::Auto : GlslCode::Tape, code == "const-tape");
    const std::string stem = fs::path(scene).stem().string();
    save_pair(p, stem);
    std::printf("%s %dx%d [%s]%s: PSNR %.2f dB, %.2f%% pixels off by > 8 (cpu %.0f ms, llvmpipe %.0f ms) -> %s\n", stem.c_str(), w, h,
                set ? set : "", baseline ? " cpu=baseline" : "", psnr(p.cpu, p.gpu), 100.0 * bad_pixels(p.cpu, p.gpu), p.cpu_ms, p.gpu_ms,
                (out_dir() / (stem + ".*.png")).string().c_str());
}
