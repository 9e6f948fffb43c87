// The GLSL backend: every opcode through the emitter, every example through every target,
// each checked by glslangValidator when it is installed (else skipped with a warning), plus
// the shape of each target's output, and that every function the shaders call is defined.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "compiler/glsl/glsl.hpp"
#include "compiler/glsl/glsl_emit.hpp"
#include "compiler/glsl/glsl_renderer.hpp"
#include "lang/load.hpp"
#include "runtime/eval/vm.hpp"
#include "support.hpp"

namespace {

using namespace sdfc;
namespace fs = std::filesystem;

std::string find_tool(const char* name) {
    const char* path = std::getenv("PATH");
    std::stringstream ss(path ? path : "/usr/bin:/bin");
    std::string dir;
    while (std::getline(ss, dir, ':')) {
        fs::path p = fs::path(dir.empty() ? "." : dir) / name;
        std::error_code ec;
        if (fs::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0) return p.string();
    }
    return "";
}

const std::string& validator() {
    static const std::string v = find_tool("glslangValidator");
    return v;
}

fs::path scratch() {
    static const fs::path d = [] {
        fs::path p = fs::temp_directory_path() / fmt::format("sdfc-test-glsl-{}", getpid());
        fs::remove_all(p);  // (an earlier process with this pid may have left files)
        fs::create_directories(p);
        return p;
    }();
    return d;
}

std::string read_text(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

// Runs glslangValidator on `src` (a complete fragment shader). Returns "" when accepted, else
// its output.
std::string validate(const std::string& src, const std::string& name) {
    const fs::path file = scratch() / (name + ".frag"), log = scratch() / (name + ".log");
    std::ofstream(file, std::ios::binary) << src;
    const std::string cmd = fmt::format("'{}' '{}' > '{}' 2>&1", validator(), file.string(), log.string());
    const int rc = std::system(cmd.c_str());
    if (rc == 0) return "";
    std::string out = read_text(log);
    return out.empty() ? "glslangValidator exited with " + std::to_string(rc) : out;
}

bool skip_without_validator() {
    if (!validator().empty()) return false;
    WARN("SKIPPED: glslangValidator is not on PATH (Debian: glslang-tools), shaders are not validated");
    return true;
}

// What shadertoy.com wraps around a shader.
std::string shadertoy_prelude(const std::string& code) {
    return "#version 300 es\nprecision highp float;\nprecision highp int;\nprecision mediump sampler3D;\n"
           "uniform vec3 iResolution;\nuniform float iTime;\nuniform float iTimeDelta;\nuniform int iFrame;\n"
           "uniform vec4 iMouse;\nuniform vec4 iDate;\nout vec4 shadertoy_out_color;\n" +
           code + "\nvoid main() { mainImage(shadertoy_out_color, gl_FragCoord.xy); }\n";
}

std::string html_shader(const std::string& page) {
    const std::string open = R"(<script type="x-shader/x-fragment" id="sdf-fragment">)";
    const size_t a = page.find(open);
    if (a == std::string::npos) return "";
    const size_t b = page.find("</script>", a);
    std::string s = page.substr(a + open.size(), b - a - open.size());
    s.erase(0, s.find_first_not_of(" \t\r\n"));
    return s;
}

std::vector<std::string> example_files() {
    std::vector<std::string> out;
    const fs::path dir = fs::path(SDFC_SOURCE_DIR) / "examples";
    if (fs::is_directory(dir))
        for (const auto& e : fs::directory_iterator(dir))
            if (e.path().extension() == ".sdf" || e.path().extension() == ".vm") out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

std::string glsl_of_text(const std::string& src, GlslTarget t) {
    SourceManager sm;
    const SourceFile& f = sm.add("scene.sdf", src);
    InterpretOptions o;
    o.time = std::nullopt;
    Scene s = interpret_source(sm, f, o);
    return emit_glsl(s, t);
}

std::string strip_outer(std::string s) {
    if (s.size() >= 2 && s.front() == '(' && s.back() == ')') {
        int depth = 0;
        for (size_t i = 0; i < s.size(); ++i) {
            if (s[i] == '(') ++depth;
            else if (s[i] == ')' && --depth == 0 && i + 1 != s.size()) return s;
        }
        return s.substr(1, s.size() - 2);
    }
    return s;
}

// The expression an op's template gives for operands p.x, p.y, p.z and k = 0.5, derived here
// from opcodes.def's text independently of the emitter.
std::string template_expr(Op op) {
    std::string t(op_info(op).glsl);
    for (auto [ph, v] : {std::pair<const char*, const char*>{"{a}", "p.x"}, {"{b}", "p.y"}, {"{c}", "p.z"}, {"{k}", "0.5"}})
        for (size_t pos; (pos = t.find(ph)) != std::string::npos;) t.replace(pos, 3, v);
    return strip_outer(t);
}

// GLSL text without its // comments.
std::string strip_comments(const std::string& src) {
    std::string out;
    std::stringstream ss(src);
    for (std::string line; std::getline(ss, line);) out += line.substr(0, line.find("//")) + "\n";
    return out;
}

// The names `src` calls: an identifier followed by '(' (so also constructors and keywords).
std::set<std::string> called(const std::string& src) {
    static const std::regex call_re(R"re(\b([A-Za-z_]\w*)\s*\()re");
    std::set<std::string> out;
    const std::string code = strip_comments(src);
    for (std::sregex_iterator it(code.begin(), code.end(), call_re), end; it != end; ++it) out.insert((*it)[1]);
    return out;
}

// The functions and structs `src` defines: a line starting `type name(` or `struct Name`.
std::set<std::string> defined(const std::string& src) {
    static const std::regex def_re(R"re(^(?:struct\s+([A-Za-z_]\w*)|[A-Za-z_]\w*\s+([A-Za-z_]\w*)\s*\())re");
    std::set<std::string> out;
    std::stringstream ss(strip_comments(src));
    for (std::string line; std::getline(ss, line);) {
        std::smatch m;
        if (std::regex_search(line, m, def_re)) out.insert(m[1].matched ? m[1].str() : m[2].str());
    }
    return out;
}

// The sdf_ helpers that opcodes.def's GLSL templates call.
std::set<std::string> template_helpers() {
    static const std::regex helper_re(R"re(\b(sdf_\w+)\s*\()re");
    std::set<std::string> out;
    for (int i = 0; i < kOpCount; ++i) {
        const std::string t(op_info(static_cast<Op>(i)).glsl);
        for (std::sregex_iterator it(t.begin(), t.end(), helper_re), end; it != end; ++it) out.insert((*it)[1]);
    }
    return out;
}

}  // namespace

TEST_CASE("glsl: float literals are valid GLSL and read back exactly", "[glsl]") {
    CHECK(glsl::literal(2.0f) == "2.0");
    CHECK(glsl::literal(0.5f) == "0.5");
    CHECK(glsl::literal(100.0f) == "100.0");
    CHECK(glsl::literal(1e-4f) == "1e-04");
    CHECK(glsl::literal(-3.0f) == "(-3.0)");
    CHECK(glsl::literal(-0.0f) == "(-0.0)");
    CHECK(glsl::literal(std::numeric_limits<float>::infinity()) == "uintBitsToFloat(0x7f800000u)");
    CHECK(glsl::literal(-std::numeric_limits<float>::infinity()) == "(-uintBitsToFloat(0x7f800000u))");
    CHECK(glsl::literal(std::nanf("")) == "uintBitsToFloat(0x7fc00000u)");
    for (float v : {0.1f, 1.0f / 3.0f, 3.4028235e38f, 1.17549435e-38f, 1e-45f, 123456789.0f, 0.70710678f, -2.5e-7f, 1e20f}) {
        std::string s = glsl::literal(v);
        INFO(s);
        CHECK((s.find('.') != std::string::npos || s.find('e') != std::string::npos));
        if (s[0] == '(') s = s.substr(1, s.size() - 2);
        CHECK(std::strtof(s.c_str(), nullptr) == v);
    }
}

TEST_CASE("glsl: negative constants print as subtraction, never as '--'", "[glsl]") {
    CHECK(glsl::op_expr(Op::AddI, "x", "", "", -2.0f) == "(x - 2.0)");
    CHECK(glsl::op_expr(Op::Neg, "(-2.0)", "", "", 0.0f) == "(-(-2.0))");
    CHECK(glsl::op_expr(Op::Sub, "x", "(-1.5)", "", 0.0f) == "(x + 1.5)");
    CHECK(glsl::op_expr(Op::MulI, "x", "", "", -2.0f) == "(x * (-2.0))");
}

TEST_CASE("glsl: every opcode goes through the emitter as its opcodes.def template", "[glsl][opcodes]") {
    std::string all = "#version 300 es\nprecision highp float;\nprecision highp int;\nfloat sdf_time;\nconst float sdf_param[4] = float[4](0.5, 1.0, 1.5, 2.0);\n";
    all += om::kGlslNoise;
    all += om::kGlslPow;
    std::string sum;
    std::vector<std::string> single;
    for (int i = 0; i < kOpCount; ++i) {
        const Op op = static_cast<Op>(i);
        const OpInfo& info = op_info(op);
        INFO("op " << info.mnemonic << " template " << info.glsl);
        // (The placeholders' agreement with the row: tests/conformance/test_table.cpp; each op's
        // value on llvmpipe: tests/conformance/test_points.cpp.)
        glsl::FunctionSpec spec;
        spec.signature = fmt::format("float op_{}(vec3 p)", info.mnemonic);
        spec.var_prefix = "v";
        spec.inline_limit = 1000;
        const std::string fn = glsl::function(test::single_op_program(op, 0.5f), spec);
        const std::string expect = template_expr(op);
        INFO("emitted:\n" << fn << "expected to contain: " << expect);
        CHECK(fn.find(expect) != std::string::npos);
        all += fn;
        sum += fmt::format(" + op_{}(q)", info.mnemonic);
        single.push_back(fn);
    }
    all += "out vec4 color;\nvoid main() {\n    vec3 q = gl_FragCoord.xyz;\n    sdf_time = q.x;\n    color = vec4(0.0" + sum + ");\n}\n";
    if (skip_without_validator()) return;
    const std::string err = validate(all, "all_opcodes");
    if (!err.empty()) {
        // Name the culprits.
        for (int i = 0; i < kOpCount; ++i) {
            const std::string one = "#version 300 es\nprecision highp float;\nprecision highp int;\nfloat sdf_time;\nconst float sdf_param[4] = float[4](0.5, 1.0, 1.5, 2.0);\n" + std::string(om::kGlslNoise) + std::string(om::kGlslPow) +
                                    single[i] + "out vec4 color;\nvoid main() { color = vec4(op_" + std::string(op_info(static_cast<Op>(i)).mnemonic) +
                                    "(gl_FragCoord.xyz)); }\n";
            const std::string e = validate(one, fmt::format("op_{}", i));
            INFO("op " << op_info(static_cast<Op>(i)).mnemonic << ":\n" << e);
            CHECK(e == "");
        }
    }
    INFO(err);
    CHECK(err == "");
}

TEST_CASE("glsl: every example compiles for every target", "[glsl][examples]") {
    const auto files = example_files();
    if (files.empty()) {
        WARN("no examples/*.sdf yet");
        return;
    }
    const bool have = !skip_without_validator();
    for (const std::string& path : files) {
        const std::string stem = fs::path(path).stem().string();
        INFO("example " << path);
        SourceManager sm;
        InterpretOptions o;
        o.time = std::nullopt;
        Scene s = load_scene(sm, path, o);

        const std::string st = emit_glsl(s, GlslTarget::Shadertoy);
        CHECK(st.find("#version") == std::string::npos);
        CHECK(st.find("uniform") == std::string::npos);
        CHECK(st.find("void main(") == std::string::npos);
        CHECK(st.find("precision ") == std::string::npos);
        CHECK(st.find("void mainImage(out vec4 fragColor, in vec2 fragCoord)") != std::string::npos);
        CHECK(st.find("float map(vec3 p)") != std::string::npos);
        CHECK(st.find("Material sdf_material(vec3 p)") != std::string::npos);
        CHECK(std::count(st.begin(), st.end(), '\n') <= 2000);  // issue 13's bound on pasted code

        const std::string g330 = emit_glsl(s, GlslTarget::Glsl330);
        CHECK(g330.rfind("#version 330 core\n", 0) == 0);
        CHECK(g330.find("uniform vec2 iResolution;") != std::string::npos);
        CHECK(g330.find("uniform float iTime;") != std::string::npos);
        CHECK(g330.find("void main()") != std::string::npos);

        const std::string page = emit_glsl(s, GlslTarget::Html);
        const std::string hs = html_shader(page);
        CHECK(hs.rfind("#version 300 es\n", 0) == 0);
        if (!have) continue;
        std::string e = validate(shadertoy_prelude(st), stem + ".shadertoy");
        INFO("shadertoy:\n" << e);
        CHECK(e == "");
        e = validate(g330, stem + ".glsl330");
        INFO("glsl330:\n" << e);
        CHECK(e == "");
        e = validate(hs, stem + ".html");
        INFO("html:\n" << e);
        CHECK(e == "");
    }
}

TEST_CASE("glsl: every sdf_ function a shader calls is defined in it, template helpers included", "[glsl]") {
    // Every example and a few scripts through every target; the scripts make sure each helper
    // an opcodes.def template calls (sdf_noise) is used by some scene.
    SourceManager sm;
    std::vector<std::pair<std::string, Scene>> scenes;
    InterpretOptions o;
    o.time = std::nullopt;
    for (const std::string& path : example_files()) scenes.emplace_back(path, load_scene(sm, path, o));
    for (const char* src : {"sphere(1);", "displace(0.1, 2) box(1);",
                            "material(color = [noise([time, 1, 2]), 1, 1]) field (p) -> length(p) - 1;",
                            "field (p) -> pow(abs(p.x), 3) + atan2(p.y, p.z) - 1;"})
        scenes.emplace_back(src, interpret_source(sm, sm.add("scene.sdf", src), o));
    const std::set<std::string> helpers = template_helpers();
    std::set<std::string> used;
    for (const auto& [what, scene] : scenes)
        for (GlslTarget t : {GlslTarget::Shadertoy, GlslTarget::Glsl330, GlslTarget::Html}) {
            std::string code = emit_glsl(scene, t);
            if (t == GlslTarget::Html) code = html_shader(code);
            const std::set<std::string> calls = called(code), defs = defined(code);
            INFO(what << ", target " << static_cast<int>(t));
            for (const std::string& c : calls) {
                if (c.rfind("sdf_", 0) != 0) continue;
                INFO("calls " << c);
                CHECK(defs.count(c) == 1);
                if (helpers.count(c)) used.insert(c);
            }
            for (const std::string& h : helpers) {
                INFO("defines " << h << " without calling it");
                CHECK((defs.count(h) == 0 || calls.count(h) == 1));
            }
        }
    for (const std::string& h : helpers) {
        INFO("no scene here calls " << h << ": add a script that uses its opcode");
        CHECK(used.count(h) == 1);
    }
}

TEST_CASE("glsl: every function the renderer's .glsl files call is defined", "[glsl]") {
    // Builtins, constructors and keywords the renderer may use; a new builtin goes here.
    const std::set<std::string> glsl = {"abs", "asin", "atan", "clamp", "cos", "cross", "dot", "exp", "floor", "isinf", "isnan", "all", "any", "bvec2", "bvec3",
                                        "length", "max", "min", "mix", "mod", "normalize", "pow", "radians", "reflect", "refract",
                                        "sin", "sqrt", "tan", "uintBitsToFloat", "bool", "float", "int", "uint", "vec2",
                                        "vec3", "vec4", "ivec3", "uvec3", "if", "for", "while", "return"};
    // What compiler/glsl/glsl.cpp writes from the scene between kRendererHead and kRendererBody.
    const std::set<std::string> scene = {"map", "sdf_material", "sdf_settings"};
    struct Part {
        const char* name;
        std::string text;
        std::set<std::string> also;
    };
    const std::string rules = glsl::shared_rules_glsl(glsl::kSharedRules);
    const Part parts[] = {{"renderer", rules + std::string(glsl::kRendererHead) + std::string(glsl::kRendererBody), scene},
                          {"noise", std::string(om::kGlslNoise), {}},
                          {"pow", std::string(om::kGlslPow), {}}};
    for (const Part& p : parts) {
        const std::set<std::string> defs = defined(p.text);
        for (const std::string& c : called(p.text)) {
            INFO(p.name << " calls " << c);
            CHECK((defs.count(c) + glsl.count(c) + p.also.count(c)) > 0);
        }
    }
    // The entry points of every target call these.
    const std::set<std::string> defs = defined(std::string(glsl::kRendererBody));
    CHECK(defs.count("sdf_render") == 1);
    CHECK(defs.count("sdf_mouse_orbit") == 1);
    CHECK(defined(std::string(om::kGlslNoise)).count("sdf_noise") == 1);
}

TEST_CASE("glsl: shadertoy output is paste-ready and readable", "[glsl]") {
    const std::string st = glsl_of_text(
        "camera(position = [0, 2, 6 + sin(time)], target = [0, 0, 0]);\n"
        "light(position = [3, 4, 5], intensity = 20);\n"
        "translate([0, 0.5 * time, 0]) sphere(2);\n"
        "displace(0.1, 2) box(1);\n",
        GlslTarget::Shadertoy);
    CHECK(st.find("#version") == std::string::npos);
    CHECK(st.find("uniform") == std::string::npos);
    CHECK(st.find("void main(") == std::string::npos);
    CHECK(st.find("iTime") != std::string::npos);
    CHECK(st.find("iMouse") != std::string::npos);
    CHECK(st.find("iResolution") != std::string::npos);
    // `time` is symbolic: used by the distance and the camera.
    const size_t map = st.find("float map(vec3 p)");
    REQUIRE(map != std::string::npos);
    CHECK(st.find("sdf_time", map) < st.find("\n}\n", map));
    const size_t set = st.find("void sdf_settings()");
    REQUIRE(set != std::string::npos);
    CHECK(st.find("sdf_time", set) < st.find("\n}\n", set));
    // Comments name the script lines; constants are float literals; noise comes along.
    CHECK(st.find("// scene.sdf:4  displace(0.1, 2) box(1);") != std::string::npos);
    CHECK(st.find("sdf_noise(") != std::string::npos);
    CHECK(st.find("float sdf_noise(vec3 q)") != std::string::npos);
    CHECK(st.find("2.0") != std::string::npos);
    if (skip_without_validator()) return;
    const std::string e = validate(shadertoy_prelude(st), "readable");
    INFO(e);
    CHECK(e == "");
}

TEST_CASE("glsl: targets for scenes with every renderer feature validate", "[glsl]") {
    const char* scenes[] = {
        // default lights, default camera
        "sphere(1);",
        // glass, mirror, emission, soft shadows, directional light, many bounces
        "light(position = [4, 6, 5], intensity = 50, radius = 0.5);\n"
        "light(direction = [-1, -2, -0.5], intensity = 0.6);\n"
        "render(max_bounces = 5, samples = 3);\n"
        "plane();\n"
        "material(color = [0.9, 0.95, 1], transparency = 0.9, ior = 1.5) sphere(1);\n"
        "translate([2, 0, 0]) material(reflect = 0.8, emission = [0.1, 0, 0]) box(1);\n",
        // orthographic, cone AA, no shadows, no AO, zero bounces
        "camera(position = [5, 5, 5], projection = \"orthographic\", ortho_height = 4);\n"
        "render(aa = \"cone\", shadows = false, ao = false, max_bounces = 0);\n"
        "torus(1, 0.3);\n",
    };
    if (skip_without_validator()) return;
    int i = 0;
    for (const char* src : scenes) {
        INFO(src);
        for (GlslTarget t : {GlslTarget::Shadertoy, GlslTarget::Glsl330, GlslTarget::Html}) {
            std::string code = glsl_of_text(src, t);
            if (t == GlslTarget::Shadertoy) code = shadertoy_prelude(code);
            if (t == GlslTarget::Html) code = html_shader(code);
            const std::string e = validate(code, fmt::format("feature{}_{}", i, static_cast<int>(t)));
            INFO("target " << static_cast<int>(t) << ":\n" << e);
            CHECK(e == "");
        }
        ++i;
    }
}

TEST_CASE("glsl: the html page is self-contained", "[glsl][html]") {
    const std::string page = glsl_of_text("sphere(1);", GlslTarget::Html);
    CHECK(page.rfind("<!DOCTYPE html>", 0) == 0);
    CHECK(page.find("getContext('webgl2'") != std::string::npos);
    CHECK(page.find("WebGL2 is not available") != std::string::npos);
    CHECK(page.find("<script src") == std::string::npos);
    CHECK(page.find("<link") == std::string::npos);
    CHECK(page.find("http://") == std::string::npos);
    CHECK(page.find("https://") == std::string::npos);
    CHECK(page.find("@SHADER@") == std::string::npos);
    CHECK(page.find("@PAGE_JS@") == std::string::npos);
    CHECK(page.find("@USES_TIME@") == std::string::npos);
    CHECK(page.find("\"uses_time\":false") != std::string::npos);
    CHECK(page.find("@SCENE@") == std::string::npos);
    CHECK(page.find("id=\"samples\"") != std::string::npos);
    CHECK(page.find("capture") != std::string::npos);
    CHECK(page.find("id=\"play\"") != std::string::npos);
    CHECK(page.find("id=\"time\"") != std::string::npos);
    CHECK(page.find("id=\"scale\"") != std::string::npos);
    // Every byte ASCII-safe for the shader compiler, even with non-ASCII script comments.
    const std::string p2 = glsl_of_text("// caf\xc3\xa9 \xe2\x80\x94 </script>\nsphere(1); // \xc3\xa9\n", GlslTarget::Html);
    const std::string hs = html_shader(p2);
    for (char c : hs) CHECK(static_cast<unsigned char>(c) < 0x80);
    CHECK(hs.find("</") == std::string::npos);
}

// LANGUAGE.md: `time` may be used anywhere, and becomes iTime in GLSL. A shape chosen by a
// condition on time compiles, with time symbolic, to both shapes and a select: the same
// distances as the script run at each time.
TEST_CASE("glsl: shapes chosen by a condition on time", "[glsl]") {
    const char* scripts[] = {
        "if (time > 1) sphere(1); else box(1);",
        "time > 1 ? material(color = [1, 0, 0]) box(1) : translate([0.5, 0, 0]) sphere(2);",
        "union { torus(1, 0.2); if (time < 0.5) { sphere(0.5); box(0.2); } }",
    };
    for (const char* src : scripts) {
        INFO(src);
        InterpretOptions symbolic;
        symbolic.time = std::nullopt;
        auto sym = test::compile_text(src, "scene.sdf", symbolic);
        for (float t : {0.25f, 2.0f}) {
            InterpretOptions at;
            at.time = t;
            auto fixed = test::compile_text(src, "scene.sdf", at);
            for (auto [x, y, z] : {std::array<float, 3>{0.9f, 0.1f, 0.2f}, {1.6f, 0, 0}, {0, 1.2f, 0.4f}, {-2, 0.5f, 0}}) {
                Evaluator ev(sym->cs.distance);
                CHECK(ev.eval1(x, y, z, t) == Approx(test::dist(fixed->cs, x, y, z)).margin(1e-5));
            }
        }
        const std::string g = glsl_of_text(src, GlslTarget::Shadertoy);
        CHECK(g.find("sdf_time") != std::string::npos);
        if (skip_without_validator()) continue;
        const std::string e = validate(shadertoy_prelude(g), "readable");
        INFO(e);
        CHECK(e == "");
    }
    // On the point, a shape still cannot be chosen.
    CHECK(test::first_error_line("field (p) -> { if (p.x > 0) sphere(1); p.x };") ==
          "test.sdf:1:24: error: a shape statement cannot depend on a condition on the point; use a field or min/max");
}

TEST_CASE("glsl: the shader carries the shared rules as GLSL and the plan's constants", "[glsl]") {
    const std::string st = glsl_of_text("plane();\ntranslate([0, 1, 0]) sphere(1);", GlslTarget::Shadertoy);
    // rules.h, turned into GLSL: no C++ left in the code, each rule defined once; its comments
    // name the macros as they are (they read "SDF_FN is dropped", not "is dropped").
    std::string code;
    for (size_t at = 0; at < st.size();) {
        size_t end = st.find('\n', at);
        if (end == std::string::npos) end = st.size();
        const std::string line = st.substr(at, end - at);
        code += line.substr(0, line.find("//")) + "\n";
        at = end + 1;
    }
    for (const char* cxx : {"SDF_FN", "SDF_INOUT", "SDF_OUT(", " SDF_AND ", " SDF_OR ", "namespace", "#pragma", "glm::"}) {
        INFO(cxx);
        CHECK(code.find(cxx) == std::string::npos);
    }
    CHECK(st.find("SDF_FN is dropped, SDF_INOUT(T) becomes") != std::string::npos);
    for (const char* rule : {"bool sdf_relaxed_step(", "bool sdf_raw_step(", "bool sdf_soft_step(", "bool sdf_cone_step(",
                             "SdfCamera sdf_make_camera(", "float sdf_to_srgb(", "vec3 sdf_blinn_phong("}) {
        INFO(rule);
        const size_t at = st.find(rule);
        CHECK(at != std::string::npos);
        CHECK(st.find(rule, at + 1) == std::string::npos);
    }
    CHECK(st.find("inout float t, inout float om") != std::string::npos);
    // The floor plane reaches the shader, with the plan's margin (that of the box of the rest, 3e-3).
    CHECK(st.find("const int SDF_NUM_PLANES = 1;") != std::string::npos);
    CHECK(st.find("const vec4 SDF_PLANES[1] = vec4[1](vec4(0.0, 1.0, 0.0, 0.003));") != std::string::npos);
    CHECK(st.find("const bool SDF_PREMARCH = true;") != std::string::npos);
    // No light in the script: the default rig, from the rules.
    CHECK(st.find("sdf_key_light_dir(fwd, right, up)") != std::string::npos);
}

TEST_CASE("glsl: a raw field's Lipschitz estimate is the same through the batch VM and the scalar reference", "[glsl]") {
    // A sphere of radius 1 scaled by 3: |grad| = 3, so 1 / (1.5 * 3) = 0.2222.
    SourceManager sm;
    const SourceFile& f = sm.add("three.vm", "_x var-x\n_y var-y\n_z var-z\n_a square _x\n_b square _y\n_c square _z\n"
                                             "_d add _a _b\n_e add _d _c\n_f sqrt _e\n_g const 3\n_h mul _f _g\n_i sub _h _g\n");
    Scene s = load_vm(sm, f);
    const std::string fast = emit_glsl(s, GlslTarget::Shadertoy, sample_batch);
    CHECK(fast == emit_glsl(s, GlslTarget::Shadertoy, sample_scalar));
    const size_t at = fast.find("const float SDF_RAW_INV_LIPSCHITZ = ");
    REQUIRE(at != std::string::npos);
    CHECK(std::stof(fast.substr(at + 36, 12)) == Approx(1.0f / 4.5f).epsilon(0.02));
    CHECK(fast.find("const bool SDF_RAW = true;") != std::string::npos);
}

// Issue 13's bound: a big scene's Shadertoy code, apart from the tape's data, stays at most
// 2,000 lines, and validates inside Shadertoy's prelude.
TEST_CASE("glsl: big scenes become a tape with bounded code", "[glsl][tape]") {
    for (const char* stem : {"tree-2047", "grid-10000"}) {
        INFO(stem);
        const std::string src = read_text(fs::path(SDFC_SOURCE_DIR) / "tests/gpu/scenes/big" / (std::string(stem) + ".sdf"));
        REQUIRE(!src.empty());
        const std::string st = glsl_of_text(src, GlslTarget::Shadertoy);
        const size_t open = st.find("const uvec4 SDF_TAPE[");
        REQUIRE(open != std::string::npos);
        const size_t close = st.find(");\n", open);
        REQUIRE(close != std::string::npos);
        const auto lines = [](const std::string& s) { return std::count(s.begin(), s.end(), '\n'); };
        CHECK(lines(st) - lines(st.substr(open, close - open)) <= 2000);
        CHECK(st.find("float map(vec3 p)") != std::string::npos);
        if (skip_without_validator()) continue;
        const std::string e = validate(shadertoy_prelude(st), std::string(stem) + ".shadertoy");
        INFO(e);
        CHECK(e == "");
    }
}

// GLSL 330 with --tape-file: the tape in a texture (NVIDIA refuses constant arrays over
// kNvidiaConstArrayTexels), the same words and the same interpreter as the html page's.
TEST_CASE("glsl: glsl330 can read its tape from a texture, the html page's words", "[glsl][tape]") {
    const std::string src = read_text(fs::path(SDFC_SOURCE_DIR) / "tests/gpu/scenes/big/tree-2047.sdf");
    REQUIRE(!src.empty());
    SourceManager sm;
    InterpretOptions o;
    o.time = std::nullopt;
    Scene s = interpret_source(sm, sm.add("tree.sdf", src), o);
    GlslOptions go;
    go.tape_texture = true;
    const GlslOutput g = compile_glsl(s, GlslTarget::Glsl330, go);
    const GlslOutput page = compile_glsl(s, GlslTarget::HtmlShader);
    REQUIRE(g.tape);
    CHECK(g.tape_texels > kNvidiaConstArrayTexels);
    CHECK(g.tape_words.size() == 4 * g.tape_texels);
    CHECK(g.tape_words == page.tape_words);
    CHECK(g.text.find("const uvec4 SDF_TAPE") == std::string::npos);
    CHECK(g.text.find("uniform highp usampler2D sdf_tape;  // RGBA32UI, 1024 texels a row\n"
                      "uvec4 sdf_texel(int i) { return texelFetch(sdf_tape, ivec2(i % 1024, i / 1024), 0); }") != std::string::npos);
    const size_t rows = (g.tape_texels + 1023) / 1024;
    CHECK(g.text.find("(little-endian uint32, " + std::to_string(g.tape_texels) + " texels) as an RGBA32UI texture 1024 texels wide and " +
                      std::to_string(rows) + " high") != std::string::npos);
    // Without the option, GLSL 330 keeps the constant array and no words.
    const GlslOutput plain = compile_glsl(s, GlslTarget::Glsl330);
    CHECK(plain.text.find("const uvec4 SDF_TAPE[") != std::string::npos);
    CHECK(plain.tape_words.empty());
    if (skip_without_validator()) return;
    const std::string e = validate(g.text, "tree.glsl330");
    INFO(e);
    CHECK(e == "");
}
