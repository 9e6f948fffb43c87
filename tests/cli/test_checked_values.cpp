// Issue 14, wrong results and messages: the command line's camera gets the script's checks,
// constants out of a function's domain are errors where they are written, a distance that
// overflowed is refused, and the messages say what is wrong.
#include <catch2/catch.hpp>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;

namespace {

std::string q(const std::string& s) { return "'" + s + "'"; }

// `sdfc check` of a one-file script: the status and the first line of stderr.
std::pair<int, std::string> check(const std::string& name, const std::string& text) {
    std::string p = test::write_temp(name, text);
    auto r = run_sdfc("check " + q(p));
    std::string first = r.err.substr(0, r.err.find('\n'));
    if (first.rfind(p, 0) == 0) first = first.substr(p.size());  // ":line:col: error: ..."
    return {r.status, first};
}

}  // namespace

TEST_CASE("camera flags get the script's checks") {
    std::string s = test::write_temp("camflags.sdf", "sphere(1);\n");
    const std::string render = "render " + q(s) + " -o " + q(test::temp_dir() + "/camflags.png") + " --width 8 --height 8 ";
    auto r = run_sdfc(render + "--camera-position 0,0,0 --camera-target 0,0,0");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: --camera-position/--camera-target: the camera's position and target are the same point\n");
    r = run_sdfc(render + "--camera-position 0,0,1e30");
    CHECK(r.status == 2);
    CHECK(r.err.find("the camera position is too far from the origin") != std::string::npos);
    r = run_sdfc(render + "--camera-position 0,5,0");  // up (0,1,0) along the view
    CHECK(r.status == 2);
    CHECK(r.err.find("parallel to the view direction") != std::string::npos);
    r = run_sdfc(render + "--camera-position 0,0,3 --quiet");
    CHECK(r.status == 0);
}

TEST_CASE("a far camera in a script is too far and not an up vector along the view") {
    auto [st, msg] = check("camfar.sdf", "camera(position = [0, 0, 1e20]);\nsphere(1);\n");
    CHECK(st == 1);
    CHECK(msg == ":1:1: error: the camera position is too far from the origin (at most 1e15 on each axis)");
    std::tie(st, msg) = check("camfar2.sdf", "camera(position = [0, 0, 1e30]);\nsphere(1);\n");
    CHECK(st == 1);
    CHECK(msg.find("too far") != std::string::npos);
    std::tie(st, msg) = check("camnear.sdf", "camera(position = [0, 0, 1e12]);\nsphere(1);\n");
    CHECK(st == 0);
}

TEST_CASE("acos and asin of a constant outside -1 to 1 are errors like sqrt(-1)") {
    auto [st, msg] = check("acos2.sdf", "sphere(acos(2));\n");
    CHECK(st == 1);
    CHECK(msg == ":1:13: error: acos of a number outside [-1, 1] (2)");
    std::tie(st, msg) = check("asin.sdf", "let a = -1.5;\nsphere(1 + asin(a));\n");
    CHECK(st == 1);
    CHECK(msg == ":2:17: error: asin of a number outside [-1, 1] (-1.5)");
    std::tie(st, msg) = check("acos1.sdf", "sphere(2 + acos(1) + asin(-1));\n");
    CHECK(st == 0);
    // In a field the argument varies: clamped, no error.
    std::tie(st, msg) = check("acosfield.sdf", "field (p) -> length(p) - 1 + 0 * acos(p.x);\n");
    CHECK(st == 0);
}

TEST_CASE("a distance that overflowed to -infinity is refused at compile time") {
    auto [st, msg] = check("overflow.sdf", "scale(1e38) sphere(1e38);\n");
    CHECK(st == 1);
    CHECK(msg.find("error: the scene's distance is not a number (-inf at the origin and at the camera)") != std::string::npos);
    std::tie(st, msg) = check("bigok.sdf", "scale(1e10) sphere(1e10);\n");
    CHECK(st == 0);
    // sdfc glsl refuses it too (its shader would draw nothing), as does every target.
    std::string p = test::write_temp("overflow_glsl.sdf", "scale(1e38) sphere(1e38);\n");
    for (const char* target : {"shadertoy", "glsl330", "html"}) {
        auto r = run_sdfc("glsl " + q(p) + " --target " + target);
        CHECK(r.status == 1);
        CHECK(r.out.empty());
        CHECK(r.err.find(p + ":1:1: error: the scene's distance is not a number (-inf at the origin and at the camera)") == 0);
    }
    CHECK(run_sdfc("glsl " + q(test::write_temp("bigok_glsl.sdf", "scale(1e10) sphere(1e10);\n"))).status == 0);
    // A size that depends on time may overflow at time 0 only: the shader is written.
    CHECK(run_sdfc("glsl " + q(test::write_temp("time_glsl.sdf", "sphere(1 / time);\n"))).status == 0);
    // A param (a uniform) is checked at its value, not at 0: polar_repeat(0) has no copies.
    const std::string counts = test::write_temp("param_count_glsl.sdf",
                                                "let n = param(4, 2, 6, 1);\nlet steps = param(3, 1, 6, 1);\n"
                                                "polar_repeat(n) translate([1, 0, 0]) sphere(0.2);\n"
                                                "stairs_union(0.3, steps) { sphere(1); translate([1, 0, 0]) box(1); }\n");
    for (const char* target : {"shadertoy", "html"}) CHECK(run_sdfc("glsl " + q(counts) + " --target " + target).status == 0);
}

TEST_CASE("math messages: normalize of a tiny vector and pow of a negative number") {
    auto [st, msg] = check("tiny.sdf", "let n = normalize([1e-30, 0, 0]);\nsphere(n.x);\n");
    CHECK(st == 0);
    std::tie(st, msg) = check("zero.sdf", "let n = normalize([0, 0, 0]);\nsphere(1);\n");
    CHECK(st == 1);
    CHECK(msg == ":1:19: error: normalize of a zero vector");
    std::tie(st, msg) = check("pow.sdf", "sphere(pow(-8, 1/3));\n");
    CHECK(st == 1);
    CHECK(msg.find(":1:12: error: pow of a negative number (-8) to a fractional power") == 0);
    std::tie(st, msg) = check("powint.sdf", "sphere(pow(-2, 2));\n");
    CHECK(st == 0);
}

TEST_CASE("a thread count above the machine's is capped quietly") {
    std::string s = test::write_temp("threads.sdf", "sphere(1);\n");
    auto r = run_sdfc("render " + q(s) + " -o " + q(test::temp_dir() + "/threads.png") +
                      " --width 16 --height 16 --threads 1000 --quiet");
    CHECK(r.status == 0);
    CHECK(r.err == "");
}

TEST_CASE("messages: size limits agree and whole numbers in full and /proc files and a byte-order mark") {
    std::string s = test::write_temp("limits14.sdf", "sphere(1);\n");
    auto r = run_sdfc("render " + q(s) + " -o " + q(test::temp_dir() + "/limits14.png") + " --width 16385");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: --width must be from 1 to 16384, not 16385\n");
    auto [st, msg] = check("bigwidth.sdf", "render(width = 2147483647);\nsphere(1);\n");
    CHECK(st == 1);
    CHECK(msg == ":1:16: error: render width must be a whole number from 1 to 16384, not 2147483648");
    // A /proc file reports a size of 0 and has text: read, and its text is what is wrong.
    std::tie(st, msg) = check("proc.sdf", "import \"/proc/self/status\";\nsphere(1);\n");
    CHECK(st == 1);
    CHECK(msg.find("is it a directory") == std::string::npos);
    auto r2 = run_sdfc("check " + q(test::write_temp("proc2.sdf", "import \"/proc/self/status\";\n")));
    CHECK(r2.err.find("/proc/self/status:1:") != std::string::npos);
    // The columns of the first line do not count the byte-order mark.
    std::tie(st, msg) = check("bom.sdf", "\xEF\xBB\xBFsphere(;\n");
    auto plain = check("nobom.sdf", "sphere(;\n");
    CHECK(st == 1);
    CHECK(msg == plain.second);
}

TEST_CASE("a .vm operation that folds to NaN is an error on its own line") {
    std::string vm = test::write_temp("ln.vm", "# vm\n_0 const -1\n_1 ln _0\n_2 var-x\n_3 add _1 _2\n");
    auto r = run_sdfc("check " + q(vm));
    CHECK(r.status == 1);
    CHECK(r.err.rfind(vm + ":3:1: error: this operation is not a finite number", 0) == 0);
}

TEST_CASE("a cone of zero height and radii names its parameters") {
    auto [st, msg] = check("cone0.sdf", "cone(0, 0, 0);\n");
    CHECK(st == 1);
    CHECK(msg == ":1:6: error: a cone needs a height h or a radius r1, r2 above zero (all three are 0)");
    std::tie(st, msg) = check("cone1.sdf", "cone(1, 0, 0);\n");
    CHECK(st == 0);
}

TEST_CASE("a .vm name defined twice is an error at the second definition") {
    std::string vm = test::write_temp("dup.vm", "_0 var-x\n_0 var-y\n");
    auto r = run_sdfc("check " + q(vm));
    CHECK(r.status == 1);
    CHECK(r.err.rfind(vm + ":2:1: error: '_0' is already defined (line 1): each name is defined once\n", 0) == 0);
}

TEST_CASE("a .vm model may divide by a zero constant: infinity of x's sign per point, as in Fidget") {
    std::string vm = test::write_temp("div0.vm", "x var-x\nc const 0\ny div x c\n");
    auto r = run_sdfc("eval " + q(vm) + " --at 1,0,0");
    CHECK(r.status == 0);
    CHECK(r.out == "inf\n");
    CHECK(run_sdfc("eval " + q(vm) + " --at -1,0,0").out == "-inf\n");
}

TEST_CASE("a NaN in a diagnostic reads nan, whatever its sign bit") {
    std::string vm = test::write_temp("sqrt.vm", "_0 const -1\n_1 sqrt _0\n_2 var-x\n_3 add _1 _2\n");
    auto r = run_sdfc("check " + q(vm));
    CHECK(r.status == 1);
    CHECK(r.err.rfind(vm + ":2:1: error: this operation is not a finite number (nan)\n", 0) == 0);
}
