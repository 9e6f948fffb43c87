// Warnings (issue 16, item 6): legal scripts that likely do not say what was meant; each is
// printed once, located, and the command still succeeds.
#include <catch2/catch.hpp>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;

namespace {
std::string q(const std::string& s) { return "'" + s + "'"; }
}  // namespace

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
    // Once for an animation, not once per frame.
    auto frames = run_sdfc("render " + q(s) + " -o " + q(test::temp_dir() + "/warn_{frame}.png") + " --frames 0:2 --width 8 --height 8 -q");
    CHECK(frames.status == 0);
    size_t n = 0;
    for (size_t at = frames.err.find("warning: this intersection"); at != std::string::npos; at = frames.err.find("warning: this intersection", at + 1)) ++n;
    CHECK(n == 1);
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
                         "--target html keeps the tape in a texture\n") != std::string::npos);
    }
    CHECK(run_sdfc("glsl " + q(s) + " --code tape --target html -o " + q(test::temp_dir() + "/many.html")).err.empty());
    CHECK(run_sdfc("glsl " + q(s) + " --code straight -o " + q(out)).err.empty());
    const std::string one = test::write_temp("one.sdf", "sphere(1);\n");
    CHECK(run_sdfc("glsl " + q(one) + " --code tape -o " + q(out)).err.empty());
}
