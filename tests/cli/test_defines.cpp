// -D NAME=VALUE (OpenSCAD's flag, issue 15) and the flags for every render(...) setting.
#include <catch2/catch.hpp>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;

namespace {
std::string q(const std::string& s) { return "'" + s + "'"; }

const char* kScript =
    "let size = 1;\n"
    "let tint = [1, 0, 0];\n"
    "let n = 3;\n"
    "for (i = [0 : n - 1]) translate([i * 3, 0, 0]) material(color = tint) sphere(size);\n";
}  // namespace

TEST_CASE("the flag -D sets a top-level let for every command") {
    const std::string s = test::write_temp("defines.sdf", kScript);
    CHECK(run_sdfc("eval " + q(s) + " --at 0,0,0").out == "-1\n");
    CHECK(run_sdfc("eval " + q(s) + " --at 0,0,0 -D size=2").out == "-2\n");
    CHECK(run_sdfc("eval " + q(s) + " --at 0,0,0 -Dsize=2*pi").out == "-6.2831855\n");  // joined, an expression
    CHECK(run_sdfc("eval " + q(s) + " --at 9,0,0").out == "2\n");
    CHECK(run_sdfc("eval " + q(s) + " --at 9,0,0 -D n=4").out == "-1\n");  // a fourth sphere
    CHECK(run_sdfc("eval " + q(s) + " --at 0,0,0 -D 'tint=[0, 1, 0]'").status == 0);
    const auto plain = run_sdfc("glsl " + q(s)), more = run_sdfc("glsl " + q(s) + " -D n=5");
    REQUIRE(plain.status == 0);
    CHECK(more.status == 0);
    CHECK(plain.out != more.out);
    CHECK(run_sdfc("check " + q(s) + " -D size=0.5").status == 0);
}

TEST_CASE("the flag -D: its errors are command-line errors, with did-you-mean") {
    const std::string s = test::write_temp("defines_bad.sdf", kScript);
    auto unknown = run_sdfc("check " + q(s) + " -D sise=2");
    CHECK(unknown.status == 2);
    CHECK(unknown.err == "sdfc: error: -D sise: the script has no top-level `let sise` (did you mean `size`?)\n");
    auto kind = run_sdfc("check " + q(s) + " -D 'size=[1, 2]'");
    CHECK(kind.status == 2);
    CHECK(kind.err == "sdfc: error: -D size=[1, 2]: the script's 'size' (line 1) is a number, not a 2-component vector\n");
    auto syntax = run_sdfc("check " + q(s) + " -D size=1+");
    CHECK(syntax.status == 2);
    CHECK(syntax.err == "sdfc: error: -D size=1+: expected an expression after the operator\n");
    auto name = run_sdfc("check " + q(s) + " -D size=nope");
    CHECK(name.status == 2);
    CHECK(name.err == "sdfc: error: -D size=nope: unknown name 'nope'\n");
    // A string's quotes eaten by the shell.
    const std::string text = test::write_temp("defines_text.sdf", "let finish = \"gold\";\ncolor(finish) sphere(1);\n");
    auto word = run_sdfc("check " + q(text) + " -D finish=red");
    CHECK(word.status == 2);
    CHECK(word.err == "sdfc: error: -D finish=red: unknown name 'red' (a string is quoted for the shell: -D 'finish=\"red\"')\n");
    CHECK(run_sdfc("check " + q(text) + " -D 'finish=\"red\"'").status == 0);
    auto form = run_sdfc("check " + q(s) + " -D size");
    CHECK(form.status == 2);
    CHECK(form.err == "sdfc: error: -D takes NAME=VALUE (a top-level let of the script and an expression), not 'size'\n");
    CHECK(run_sdfc("check " + q(s) + " -D size=1 -D size=2").err == "sdfc: error: -D size is given twice\n");
    CHECK(run_sdfc("check " + q(s) + " -D 'size = 2'").status == 0);  // as OpenSCAD's -D
    CHECK(run_sdfc("check " + q(s) + " -D 'size = 2' -D size=3").err == "sdfc: error: -D size is given twice\n");
    CHECK(run_sdfc("check " + q(s) + " -D \"$(printf 'size=\\377')\"").err == "sdfc: error: -D size: the value is not text (a NUL byte or invalid UTF-8)\n");
    CHECK(run_sdfc("check " + q(s) + " -D").err == "sdfc: error: -D needs a value\n");
    // A let of an imported file: -D names the main script's own.
    test::write_temp("defines_lib.sdf", "let wall = 2;\n");
    const std::string main = test::write_temp("defines_main.sdf", "import \"defines_lib.sdf\";\nsphere(wall);\n");
    CHECK(run_sdfc("check " + q(main) + " -D wall=3").err ==
          "sdfc: error: -D wall: 'wall' is an imported file's let; -D sets the main script's own top-level lets\n");
    const std::string vm = test::write_temp("defines.vm", "_0 var-x\n_1 var-y\n_2 var-z\n_3 add _0 _1\n_4 add _3 _2\n");
    auto model = run_sdfc("check " + q(vm) + " -D a=1");
    CHECK(model.status == 2);
    CHECK(model.err == "sdfc: error: -D a: a .vm model has no `let` to set\n");
}

TEST_CASE("every render(...) setting has a flag") {
    const std::string scene = test::example("showcase.sdf");
    const std::string a = test::temp_dir() + "/flags_a.png", b = test::temp_dir() + "/flags_b.png";
    REQUIRE(run_sdfc("render " + q(scene) + " -o " + q(a) + " --width 48 --height 36 -q").status == 0);
    for (const char* flag : {"--shadows off", "--ao off", "--max-steps 8", "--max-bounces 0", "--max-distance 3", "--epsilon 0.05"}) {
        INFO(flag);
        REQUIRE(run_sdfc("render " + q(scene) + " -o " + q(b) + " --width 48 --height 36 -q " + flag).status == 0);
        CHECK(test::slurp(a) != test::slurp(b));
    }
    CHECK(run_sdfc("render " + q(scene) + " -o " + q(b) + " --aa cone --samples 2 --width 8 --height 8 -q").status == 0);
    CHECK(run_sdfc("render " + q(scene) + " -o " + q(b) + " --shadows no").err == "sdfc: error: --shadows takes on or off, not 'no'\n");
    CHECK(run_sdfc("render " + q(scene) + " -o " + q(b) + " --aa foo").err == "sdfc: error: --aa takes grid or cone, not 'foo'\n");
    CHECK(run_sdfc("render " + q(scene) + " -o " + q(b) + " --epsilon 0").err == "sdfc: error: --epsilon must be above 0, not 0\n");
    CHECK(run_sdfc("render " + q(scene) + " -o " + q(b) + " --max-steps 0").err ==
          "sdfc: error: --max-steps must be from 1 to 100000, not 0\n");
    CHECK(run_sdfc("bench " + q(scene) + " --width 8 --height 8 --repeat 1 --ao off").status == 0);
}

TEST_CASE("render warns when the camera is inside the solid or looks away from the scene") {
    const std::string in = test::write_temp("view_inside.sdf", "camera(position = [0, 0, 0.5]); sphere(1);\n");
    const std::string out = test::temp_dir() + "/view.png";
    auto inside = run_sdfc("render " + q(in) + " -o " + q(out) + " --width 8 --height 8");
    CHECK(inside.status == 0);
    CHECK(inside.err.rfind("sdfc: warning: the camera (at 0, 0, 0.5) is inside the scene's solid: the picture shows it from within\n", 0) == 0);
    const std::string away = test::write_temp("view_away.sdf", "camera(position = [0, 0, 5], target = [0, 0, 10]); sphere(1);\n");
    CHECK(run_sdfc("render " + q(away) + " -o " + q(out) + " --width 8 --height 8").err.rfind(
              "sdfc: warning: nothing of the scene is in view: the camera at 0, 0, 5 looks at 0, 0, 10, away from the scene's bounds [-1, -1, -1] .. [1, "
              "1, 1]\n",
              0) == 0);
    const std::string fine = test::write_temp("view_fine.sdf", "camera(position = [0, 0, 150]); sphere(20);\n");
    CHECK(run_sdfc("render " + q(fine) + " -o " + q(out) + " --width 8 --height 8").err.find("warning") == std::string::npos);
    CHECK(run_sdfc("render " + q(in) + " -o " + q(out) + " --width 8 --height 8 -q").err.empty());
    // Unbounded scenes too: a repetition, a field.
    for (const char* body : {"repeat([2, 2, 2]) sphere(0.4);", "field (p) -> length(mod(p + 1, 2) - 1) - 0.4;"}) {
        const std::string rep = test::write_temp("view_repeat.sdf", std::string("camera(position = [0, 2, 6]);\n") + body + "\n");
        CHECK(run_sdfc("render " + q(rep) + " -o " + q(out) + " --width 8 --height 8").err.rfind(
                  "sdfc: warning: the camera (at 0, 2, 6) is inside the scene's solid: the picture shows it from within\n", 0) == 0);
    }
}
