// Warnings (issue 16, item 6): legal scripts that likely do not say what was meant; each is
// printed once, located, and the command still succeeds.
#include <catch2/catch.hpp>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;

namespace {
std::string q(const std::string& s) { return "'" + s + "'"; }
}  // namespace

TEST_CASE("a name bound nowhere, in code that has not run, is a warning with the error's hints") {
    const std::string lib = test::write_temp("warn_lib.sdf", "def wheel(r) = rotate(x = 90) cylinder(0.2, r);\n");
    const std::string s = test::write_temp("warn_names.sdf",
                                           "import \"warn_lib.sdf\";\n"
                                           "def g() = sphre(1);\n"
                                           "def h(k) = [for (i = [0 : k]) i * 2];\n"
                                           "if (false) cube(1);\n"
                                           "let f = field (p) -> length(p) - 1;\n"
                                           "wheel(1);\n");
    auto r = run_sdfc("check " + q(s));
    CHECK(r.status == 0);
    CHECK(r.err == s + ":2:11: warning: unknown name 'sphre' (did you mean `sphere`?), in code that has not run (a def never called, "
                       "a branch not taken)\ndef g() = sphre(1);\n          ^\n" +
                       s + ":4:12: warning: unknown name 'cube' (sdfc's is `box(size)`, centred on the origin), in code that has not "
                           "run (a def never called, a branch not taken)\nif (false) cube(1);\n           ^\n");
    // Every name of a valid script is bound somewhere: no warning.
    CHECK(run_sdfc("check " + q(test::example("showcase.sdf"))).err.empty());
    (void)lib;
    // A field's body runs when the scene compiles: its unknown name is the error, not also a
    // warning that it has not run.
    const std::string f = test::write_temp("warn_field.sdf", "field (p) -> lenght(p) - 1;\n");
    r = run_sdfc("check " + q(f));
    CHECK(r.status == 1);
    CHECK(r.err == f + ":1:14: error: unknown name 'lenght' (did you mean `length`?)\nfield (p) -> lenght(p) - 1;\n             ^\n");
}

TEST_CASE("a range written with its start above its end is empty and a warning, a computed one is quietly empty") {
    const std::string s = test::write_temp("warn_range.sdf",
                                           "for (i = [10 : 0]) translate([i, 0, 0]) sphere(1);\n"
                                           "let n = 0;\nfor (i = [1 : n]) sphere(i);\nsphere(1);\n"
                                           "for (i = [0 : -1 : 10]) sphere(i);\n");
    auto r = run_sdfc("check " + q(s));
    CHECK(r.status == 0);
    CHECK(r.err == s + ":1:10: warning: the range [10 : 0] is empty (its start is above its end): for a count down write "
                       "[10 : -1 : 0]\nfor (i = [10 : 0]) translate([i, 0, 0]) sphere(1);\n         ^\n" +
                       s + ":5:10: warning: the range [0 : -1 : 10] is empty (its step goes away from its end)\n"
                           "for (i = [0 : -1 : 10]) sphere(i);\n         ^\n");
}

TEST_CASE("warnings for one-operand CSG, an empty difference and an ignored alpha") {
    const std::string s = test::write_temp("warn.sdf",
                                           "intersection { sphere(1); }\n"
                                           "difference { }\n"
                                           "smooth_difference(0.1) { box(1); }\n"
                                           "color([1, 0, 0, 0.5]) sphere(1);\n"
                                           "intersection { sphere(1); box(1.5); }\n");
    auto r = run_sdfc("check " + q(s));
    CHECK(r.status == 0);
    CHECK(r.err == s + ":1:1: warning: this intersection has one operand: it is that shape (a second shape is missing?)\n"
                       "intersection { sphere(1); }\n^\n" +
                       s + ":2:1: warning: this difference has no operands: it is empty\ndifference { }\n^\n" + s +
                       ":3:1: warning: this smooth_difference has one operand: it cuts nothing away (a second shape is missing?)\n"
                       "smooth_difference(0.1) { box(1); }\n^\n" +
                       s + ":4:7: warning: color's alpha (the 4th component) is ignored: for see-through, material(transparency = ...)\n"
                           "color([1, 0, 0, 0.5]) sphere(1);\n      ^\n");
    // OpenSCAD's color(c, alpha): taken, the alpha ignored with a warning (not at alpha = 1).
    const std::string alpha = test::write_temp("warn_alpha.sdf", "color(\"red\", 0.5) sphere(1);\ncolor(\"red\", alpha = 1) box(1);\n");
    auto a = run_sdfc("check " + q(alpha));
    CHECK(a.status == 0);
    CHECK(a.err == alpha + ":1:14: warning: color's alpha is ignored: for see-through, material(transparency = ...)\n"
                           "color(\"red\", 0.5) sphere(1);\n             ^\n");
    const std::string hex = test::write_temp("warn_hex_alpha.sdf", "color(\"#ff000080\") sphere(1);\ncolor(\"#f00f\") box(1);\n");
    CHECK(run_sdfc("check " + q(hex)).err == hex + ":1:7: warning: the colour's alpha is ignored: for see-through, material(transparency = ...)\n"
                                              "color(\"#ff000080\") sphere(1);\n      ^\n");
    // Once for an animation, not once per frame.
    auto frames = run_sdfc("render " + q(s) + " -o " + q(test::temp_dir() + "/warn_{frame}.png") + " --frames 0:2 --width 8 --height 8 -q");
    CHECK(frames.status == 0);
    size_t n = 0;
    for (size_t at = frames.err.find("warning: this intersection"); at != std::string::npos; at = frames.err.find("warning: this intersection", at + 1)) ++n;
    CHECK(n == 1);
}

TEST_CASE("a light or camera inside an operation's target is a warning: operations move shapes only") {
    const std::string s = test::write_temp("warn_setting.sdf",
                                           "sphere(1);\n"
                                           "for (i = [0 : 3]) translate([i, 0, 0]) { light(position = [5, 0, 5], intensity = 30); }\n"
                                           "mirror([1, 0, 0]) camera(position = [0, 0, 6]);\n");
    auto r = run_sdfc("check " + q(s));
    CHECK(r.status == 0);
    CHECK(r.err == s + ":2:42: warning: light(...) is inside the target of translate, which applies to shapes only: the light is set "
                       "as written, not moved, turned or scaled (write it outside the operation)\n"
                       "for (i = [0 : 3]) translate([i, 0, 0]) { light(position = [5, 0, 5], intensity = 30); }\n"
                       "                                         ^\n" +
                       s + ":3:19: warning: camera(...) is inside the target of mirror, which applies to shapes only: the camera is set "
                           "as written, not moved, turned or scaled (write it outside the operation)\n"
                           "mirror([1, 0, 0]) camera(position = [0, 0, 6]);\n                  ^\n");
}

// Measured on NVIDIA's driver (580, an H200): an array constructor of more than 1,024 uvec4s
// fails to compile, so a Shadertoy or GLSL 330 shader whose tape is bigger says so.
TEST_CASE("glsl warns when a tape is too big for NVIDIA's constant arrays, and only then") {
    const std::string s = test::write_temp("many.sdf", "for (i = [0 : 999]) translate([i % 40, 0, floor(i / 40)]) sphere(0.4);\n");
    const std::string out = test::temp_dir() + "/many.glsl";
    for (const char* target : {"shadertoy", "glsl330"}) {
        auto r = run_sdfc("glsl " + q(s) + " --code tape --target " + target + " -o " + q(out));
        CHECK(r.status == 0);
        CHECK(r.err.rfind("sdfc: warning: the scene's tape is one constant array of ", 0) == 0);
        CHECK(r.err.find(" uvec4s: NVIDIA's GLSL compiler takes at most 1024 (error C1068: too much data in type constructor); "
                         "--target html (or glsl330 with --tape-file) keeps the tape in a texture\n") != std::string::npos);
    }
    CHECK(run_sdfc("glsl " + q(s) + " --code tape --target html -o " + q(test::temp_dir() + "/many.html")).err.empty());
    CHECK(run_sdfc("glsl " + q(s) + " --code straight -o " + q(out)).err.empty());
    const std::string one = test::write_temp("one.sdf", "sphere(1);\n");
    CHECK(run_sdfc("glsl " + q(one) + " --code tape -o " + q(out)).err.empty());
}

// glsl330 --tape-file: the tape as the texture's data, whole rows of 1024 RGBA32UI texels,
// little-endian; no warning; only with glsl330 and a tape.
TEST_CASE("glsl330 --tape-file writes the tape for a texture, and refuses what cannot work") {
    const std::string s = test::write_temp("many_tex.sdf", "for (i = [0 : 999]) translate([i % 40, 0, floor(i / 40)]) sphere(0.4);\n");
    const std::string out = test::temp_dir() + "/many_tex.glsl", tape = test::temp_dir() + "/many_tex.tape";
    std::remove(tape.c_str());
    auto r = run_sdfc("glsl " + q(s) + " --target glsl330 --tape-file " + q(tape) + " -o " + q(out));
    CHECK(r.status == 0);
    CHECK(r.err.empty());
    const std::string shader = test::slurp(out), bytes = test::slurp(tape);
    CHECK(shader.find("uniform highp usampler2D sdf_tape;") != std::string::npos);
    CHECK(shader.find("const uvec4 SDF_TAPE") == std::string::npos);
    // The header names the texels; the file holds whole rows of them, zero-padded.
    const size_t at = shader.find("(little-endian uint32, ");
    REQUIRE(at != std::string::npos);
    const size_t texels = std::stoul(shader.substr(at + 23));
    CHECK(texels > 1024);
    CHECK(bytes.size() == (texels + 1023) / 1024 * 1024 * 16);
    REQUIRE(bytes.size() >= texels * 16);
    CHECK(bytes.find_first_not_of('\0') < 16);  // the first texel holds an instruction
    CHECK(bytes.find_first_not_of('\0', texels * 16) == std::string::npos);
    auto bad = run_sdfc("glsl " + q(s) + " --tape-file " + q(tape) + " -o " + q(out));
    CHECK(bad.status == 2);
    CHECK(bad.err == "sdfc: error: --tape-file is for --target glsl330 (Shadertoy cannot load a file; the html page holds its tape)\n");
    bad = run_sdfc("glsl " + q(s) + " --target glsl330 --code straight --tape-file " + q(tape) + " -o " + q(out));
    CHECK(bad.status == 2);
    CHECK(bad.err == "sdfc: error: --tape-file writes a tape: it does not go with --code straight\n");
    bad = run_sdfc("glsl " + q(s) + " --target glsl330 --tape-file " + q(out) + " -o " + q(out));
    CHECK(bad.status == 2);
    CHECK(bad.err == "sdfc: error: --tape-file and the shader would both go to '" + out + "'\n");
    bad = run_sdfc("glsl " + q(s) + " --target glsl330 --tape-file -");
    CHECK(bad.status == 2);
    CHECK(bad.err == "sdfc: error: --tape-file and the shader would both go to '-'\n");
    bad = run_sdfc("glsl " + q(s) + " --target glsl330 --tape-file " + q(test::temp_dir() + "/no/such/dir/t.tape") + " -o " + q(out));
    CHECK(bad.status != 0);
    // The shader and its tape come together or not at all: a shader that cannot be written
    // leaves no tape (nor its temporary file).
    const std::string tape2 = test::temp_dir() + "/many_tex2.tape";
    std::remove(tape2.c_str());
    bad = run_sdfc("glsl " + q(s) + " --target glsl330 --tape-file " + q(tape2) + " -o /dev/full");
    CHECK(bad.status == 1);
    CHECK(bad.err == "sdfc: error: cannot write '/dev/full': No space left on device\n");
    CHECK(!std::ifstream(tape2).good());
    bad = run_sdfc("glsl " + q(s) + " --target glsl330 --tape-file " + q(tape2) + " -o " + q(test::temp_dir() + "/no/such/dir/s.glsl"));
    CHECK(bad.status != 0);
    CHECK(!std::ifstream(tape2).good());
    for (const auto& e : std::filesystem::directory_iterator(test::temp_dir()))
        CHECK(e.path().filename().string().rfind(".many_tex2", 0) == std::string::npos);
}

TEST_CASE("a missing semicolon after a def's shape is an error, after a let's material a warning, a let below its use named") {
    const std::string d = test::write_temp("warn_semi_def.sdf", "def ring(r) = torus(r, 0.1)\nsphere(1);\n");
    auto r = run_sdfc("check " + q(d));
    CHECK(r.status == 1);
    CHECK(r.err == d + ":1:15: error: a shape is written before a shape but is not an operation (is a ';' missing after it?)\n"
                       "def ring(r) = torus(r, 0.1)\n              ^\n");
    const std::string m = test::write_temp("warn_semi_let.sdf", "let m = material(color = [1, 0, 0])\nsphere(1);\n");
    r = run_sdfc("check " + q(m));
    CHECK(r.status == 0);
    CHECK(r.err == m + ":1:5: warning: the scene has no shapes, but 'm' holds one: write `m;` to add it (or is the ';' at the end "
                       "of this let missing?)\nlet m = material(color = [1, 0, 0])\n    ^\n");
    const std::string u = test::write_temp("warn_let_below.sdf", "sphere(r);\nlet r = 1;\n");
    r = run_sdfc("check " + q(u));
    CHECK(r.status == 1);
    CHECK(r.err == u + ":1:8: error: unknown name 'r' here: it is defined below, at line 2 (a let takes effect from its line on; "
                       "move it above its first use)\nsphere(r);\n       ^\n");
}

TEST_CASE("names bound nowhere are shown 20 at a time, each with its nearest name, then counted") {
    std::string text;
    for (int i = 0; i < 3000; ++i) text += "def g" + std::to_string(i) + "() = sphre(1);\n";
    const std::string s = test::write_temp("warn_many.sdf", text + "sphere(1);\n");
    auto r = run_sdfc("check " + q(s));
    CHECK(r.status == 0);
    CHECK(r.err.find(s + ":20:13: warning: unknown name 'sphre' (did you mean `sphere`?), in code that has not run") != std::string::npos);
    CHECK(r.err.find(s + ":21:13: warning: 2980 more names bound nowhere, in code that has not run (this is the first)\n") != std::string::npos);
    CHECK(r.err.find(":22:") == std::string::npos);
}

TEST_CASE("an empty operand that empties a difference or an intersection is a warning") {
    const std::string s = test::write_temp("warn_empty_operand.sdf",
                                           "let n = 0;\n"
                                           "difference { for (i = [1 : n]) box(1); sphere(1); }\n"
                                           "difference { sphere(1); for (i = [1 : n]) box(1); }\n"
                                           "intersection { sphere(2); if (n > 0) box(1); }\n");
    auto r = run_sdfc("check " + q(s));
    CHECK(r.status == 0);
    CHECK(r.err == s + ":2:14: warning: this operand of the difference adds no shape (a false condition, a loop without iterations): "
                       "the difference is empty\ndifference { for (i = [1 : n]) box(1); sphere(1); }\n             ^\n" +
                       s + ":4:27: warning: this operand of the intersection adds no shape (a false condition, a loop without "
                           "iterations): the intersection is empty\nintersection { sphere(2); if (n > 0) box(1); }\n"
                           "                          ^\n");
}

TEST_CASE("check says when only time 0 makes the error (glsl, time left open, takes the script)") {
    const std::string s = test::write_temp("check_time0.sdf", "sphere(0.5 + 0.1 * sin(1 / time));\n");
    auto r = run_sdfc("check " + q(s));
    CHECK(r.status == 1);
    CHECK(r.err.rfind(s + ":1:26: error: division by zero (at time 0, where check reads the script; other times may not fail: render --time T)\n", 0) == 0);
    CHECK(run_sdfc("glsl " + q(s) + " -o " + q(test::temp_dir() + "/check_time0.glsl")).status == 0);
    // An error at every time has no such note.
    const std::string always = test::write_temp("check_always.sdf", "sphere(1 / 0);\n");
    CHECK(run_sdfc("check " + q(always)).err.rfind(always + ":1:10: error: division by zero\n", 0) == 0);
}
