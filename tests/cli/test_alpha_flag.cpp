// render --alpha (issue 20): on by default for EXR, asked for elsewhere; formats without an
// alpha channel refuse it before any work.
#include <catch2/catch.hpp>

#include <filesystem>

#include "run.hpp"
#include "runtime/io/image.hpp"

using namespace sdfc;
using test::run_sdfc;

namespace {
std::string q(const std::string& s) { return "'" + s + "'"; }
}  // namespace

TEST_CASE("render --alpha: default on for exr, on request for png, refused for jpg") {
    const std::string s = test::write_temp("alpha.sdf", "background([0.2, 0.4, 0.6]);\nsphere(1);\n");
    const std::string dir = test::temp_dir();
    const std::string size = " --width 24 --height 16 -q";
    REQUIRE(run_sdfc("render " + q(s) + " -o " + q(dir + "/a.exr") + size).status == 0);
    CHECK(read_image(dir + "/a.exr").channels == 4);
    CHECK(read_image(dir + "/a.exr").pixels[3] == 0.0f);  // the corner's alpha
    REQUIRE(run_sdfc("render " + q(s) + " -o " + q(dir + "/b.exr") + " --alpha off" + size).status == 0);
    CHECK(read_image(dir + "/b.exr").channels == 3);
    REQUIRE(run_sdfc("render " + q(s) + " -o " + q(dir + "/c.png") + " --alpha on" + size).status == 0);
    CHECK(read_image(dir + "/c.png").channels == 4);
    REQUIRE(run_sdfc("render " + q(s) + " -o " + q(dir + "/d.png") + size).status == 0);
    CHECK(read_image(dir + "/d.png").channels == 3);
    auto jpg = run_sdfc("render " + q(s) + " -o " + q(dir + "/e.jpg") + " --alpha on" + size);
    CHECK(jpg.status == 2);
    CHECK(jpg.err == "sdfc: error: --alpha on: jpg has no alpha channel (exr, png, tif and tga have)\n");
    CHECK_FALSE(std::filesystem::exists(dir + "/e.jpg"));
    CHECK(run_sdfc("render " + q(s) + " -o " + q(dir + "/f.png") + " --alpha maybe").err == "sdfc: error: --alpha takes on or off, not 'maybe'\n");
    auto piped = run_sdfc("render " + q(s) + " -o - --format exr" + size);
    CHECK(piped.status == 0);
}
