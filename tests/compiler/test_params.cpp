// param(value, min, max, step), sdfc's extension: a constant on the CPU (or -D's value), a
// slot of sdf_param[] in GLSL (a #define for Shadertoy, a uniform the html page's slider
// sets), and its errors. The pictures: tests/gpu (llvmpipe and Chromium).
#include <catch2/catch.hpp>

#include <string>

#include "compiler/glsl/glsl.hpp"
#include "lang/interpreter.hpp"
#include "support.hpp"

namespace {

using namespace sdfc;

Scene symbolic(SourceManager& sm, const std::string& src) {
    const SourceFile& f = sm.add("scene.sdf", src);
    InterpretOptions o;
    o.time = std::nullopt;
    return interpret_source(sm, f, o);
}

// The first line of the diagnostics of the GLSL (time symbolic) reading of `src`.
std::string glsl_error(const std::string& src) {
    SourceManager sm;
    try {
        symbolic(sm, src);
    } catch (const CompileError& e) {
        const std::string s = e.formatted();
        return s.substr(0, s.find('\n'));
    }
    return "";
}

const char* kTwo =
    "let size = param(0.7, 0.2, 1.5);\n"
    "let lift = param(0, -0.5, 1, 0.25);\n"
    "translate([0, lift, 0]) sphere(size);\n";

}  // namespace

TEST_CASE("params: the CPU takes the value, or -D's") {
    CHECK(test::dist_of(kTwo, 2, 0, 0) == Approx(1.3f));
    SourceManager sm;
    const SourceFile& f = sm.add("scene.sdf", kTwo);
    InterpretOptions o;
    o.defines = {{"size", "1"}, {"lift", "0.5"}};
    Scene s = interpret_source(sm, f, o);
    CompiledScene cs = compile_scene(s);
    CHECK(test::dist(cs, 2, 0.5f, 0) == Approx(1.0f));
    CHECK(s.params.empty());
}

TEST_CASE("params: GLSL reads them from sdf_param[]") {
    SourceManager sm;
    const Scene s = symbolic(sm, kTwo);
    REQUIRE(s.params.size() == 2);
    CHECK(s.params[0].name == "size");
    CHECK(s.params[0].value == 0.7f);
    CHECK(s.params[1].min == -0.5f);
    CHECK(s.params[1].step == 0.25f);
    CHECK(s.params[0].step == 0.001f);  // (0.2 to 1.5 by default: a power of ten, so round values lie on the slider)
    CHECK(s.params[0].loc.line == 1);
    const std::string st = emit_glsl(s, GlslTarget::Shadertoy);
    CHECK(st.find("#define SDF_PARAM_size 0.7  // in [0.2, 1.5]; line 1") != std::string::npos);
    CHECK(st.find("const float sdf_param[2] = float[2](SDF_PARAM_size, SDF_PARAM_lift);") != std::string::npos);
    CHECK(st.find("sdf_param[int(0.0)]") != std::string::npos);
    const std::string page = emit_glsl(s, GlslTarget::Html);
    CHECK(page.find("uniform float sdf_param[2];") != std::string::npos);
    CHECK(page.find("var paramValues = Object.create(null)") != std::string::npos);  // (a param named constructor)
    CHECK(page.find("is over this GPU\\'s texture size") != std::string::npos);  // (a tape taller than MAX_TEXTURE_SIZE)
    CHECK(page.find("{\"name\":\"lift\",\"value\":0,\"min\":-0.5,\"max\":1,\"step\":0.25,\"uniform\":\"sdf_param[1]\"}") !=
          std::string::npos);
}

TEST_CASE("params: glsl's -D sets where a param's slider starts, and the slider stays") {
    SourceManager sm;
    const SourceFile& f = sm.add("scene.sdf", kTwo + std::string("let r = 2 * param(1);\nsphere(r);\n"));
    InterpretOptions o;
    o.time = std::nullopt;
    o.defines = {{"size", "1"}, {"lift", "3"}, {"r", "5"}};
    const Scene s = interpret_source(sm, f, o);
    REQUIRE(s.params.size() == 2);  // r is computed from its param: -D gives r its value, a number
    CHECK(s.params[0].name == "size");
    CHECK(s.params[0].value == 1.0f);
    CHECK(s.params[0].min == 0.2f);
    CHECK(s.params[0].max == 1.5f);
    CHECK(s.params[1].value == 3.0f);  // beyond the script's [-0.5, 1]: the range grows to hold it
    CHECK(s.params[1].max == 3.0f);
    CHECK(s.params[1].step == 0.25f);
    CHECK(emit_glsl(s, GlslTarget::Shadertoy).find("#define SDF_PARAM_size 1.0  // in [0.2, 1.5]; line 1") != std::string::npos);
    // A script's own def named param makes no slider: -D gives the let its value.
    SourceManager sm2;
    const SourceFile& own = sm2.add("own.sdf", "def param(x) = x * 2;\nlet n = param(1);\nsphere(n);\n");
    InterpretOptions o2;
    o2.time = std::nullopt;
    o2.defines = {{"n", "3"}};
    const Scene s2 = interpret_source(sm2, own, o2);
    CHECK(s2.params.empty());
    CHECK(test::dist(compile_scene(s2), 0, 0, 0) == Approx(-3.0f));
}

TEST_CASE("params: a name GLSL reserves (a '__' in its define) gets its index") {
    SourceManager sm;
    const Scene s = symbolic(sm, "let _r = param(1, 0.5, 2);\nlet my__r = param(1);\nlet ok_r = param(1);\nsphere(_r + my__r + ok_r);\n");
    const std::string st = emit_glsl(s, GlslTarget::Shadertoy);
    CHECK(st.find("#define SDF_PARAM_0_r 1.0  // _r in [0.5, 2.0]; line 1") != std::string::npos);
    CHECK(st.find("#define SDF_PARAM_1_my_r 1.0  // my__r in") != std::string::npos);
    CHECK(st.find("#define SDF_PARAM_ok_r 1.0  // in") != std::string::npos);
    CHECK(st.find("SDF_PARAM__") == std::string::npos);  // (comments may quote the name)
    CHECK(st.find("SDF_PARAM_my__r") == std::string::npos);
}

TEST_CASE("params: what a script cannot do with them") {
    CHECK(test::first_error_line("sphere(param(1));") ==
          "test.sdf:1:8: error: param(...) gives a top-level let its value, which the html page's slider turns: let size = "
          "param(1, 0.1, 3);");
    CHECK(test::first_error_line("def f(r) = sphere(param(r));\nf(1);") ==
          "test.sdf:1:19: error: param(...) gives a top-level let its value, which the html page's slider turns: let size = "
          "param(1, 0.1, 3); (in f, called at line 2)");
    CHECK(test::first_error_line("let r = param(5, 0, 1);\nsphere(r);") == "test.sdf:1:15: error: the param's value 5 is outside [0, 1]");
    CHECK(test::first_error_line("let r = param(0.5, 1, 0);\nsphere(r);") ==
          "test.sdf:1:23: error: the param's max (0) must be above its min (1)");
    CHECK(test::first_error_line("let r = param(0.5, 0, 1, 0);\nsphere(r);") == "test.sdf:1:26: error: the param's step must be above 0");
    CHECK(test::first_error_line("let r = param(\"a\");\nsphere(r);") == "test.sdf:1:15: error: the param's value must be a number, not a string");
    CHECK(test::first_error_line("let r = param(1, 0, 2, 1, 3);\nsphere(r);") ==
          "test.sdf:1:9: error: param takes 1 to 4 arguments (value, min, max, step), not 5");
    CHECK(test::first_error_line("let r = param(0.5) + param(0.2);\nsphere(r);") ==
          "test.sdf:1:22: error: 'r' has a param(...) already: one a let, each its own slider");
    // Each is a uniform: the page's shader must link on every WebGL2.
    std::string many;
    for (int i = 0; i < 65; ++i) many += "let p" + std::to_string(i) + " = param(1);\n";
    CHECK(glsl_error(many + "sphere(p0);") == "scene.sdf:65:11: error: a script has at most 64 params");
    // A shape's structure cannot follow a slider: GLSL says so, the CPU takes the value.
    const char* loop = "let n = param(3, 1, 8, 1);\nfor (i = [0 : n]) translate([i, 0, 0]) sphere(0.3);";
    CHECK(glsl_error(loop) ==
          "scene.sdf:2:15: error: a range's end must be known when the script runs (it depends on the point, on time or on a param)");
    CHECK(test::error_of(loop) == "");
}
