// Start-up (issue 15): image I/O is a module (libsdfc_image.so) opened at the first image
// read or write, so the commands that write no image never load OpenImageIO; the preview's
// HTTP server is one too (libsdfc_preview.so).
#include <catch2/catch.hpp>

#include <filesystem>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;
namespace fs = std::filesystem;

namespace {
std::string q(const std::string& s) { return "'" + s + "'"; }
const char* kNoModule = "SDFC_IMAGE_MODULE=/nonexistent/libsdfc_image.so";
}  // namespace

#ifndef SDFC_IMAGE_BUILTIN  // a sanitizer or fuzz build links image I/O in (CMakeLists.txt)
TEST_CASE("the sdfc binary itself needs no OpenImageIO library") {
    const std::string list = test::temp_dir() + "/ldd.txt";
    REQUIRE(std::system(("ldd '" + std::string(SDFC_BIN_PATH) + "' >'" + list + "' 2>&1").c_str()) == 0);
    const std::string libs = test::slurp(list);
    CHECK(libs.find("libtbb") != std::string::npos);  // the list is real
    CHECK(libs.find("OpenImageIO") == std::string::npos);
    CHECK(libs.find("opencv") == std::string::npos);
    // Nor the preview's HTTP server (libsdfc_preview.so) with its TLS and compression.
    CHECK(libs.find("httplib") == std::string::npos);
    CHECK(libs.find("libssl") == std::string::npos);
}

TEST_CASE("preview without its module says so before serving") {
    const std::string s = test::write_temp("startup_preview.sdf", "sphere(1);\n");
    auto r = run_sdfc("preview " + q(s) + " --port 0", "SDFC_PREVIEW_MODULE=/nonexistent/libsdfc_preview.so");
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot load the preview server libsdfc_preview.so: not found (looked for /nonexistent/libsdfc_preview.so)\n");
}

TEST_CASE("commands that write no image run without the image module") {
    const std::string s = test::write_temp("startup.sdf", "sphere(1);\n");
    CHECK(run_sdfc("--version", kNoModule).status == 0);
    CHECK(run_sdfc("check " + q(s), kNoModule).status == 0);
    CHECK(run_sdfc("eval " + q(s) + " --at 2,0,0", kNoModule).out == "1\n");
    CHECK(run_sdfc("glsl " + q(s) + " -o " + q(test::temp_dir() + "/startup.glsl"), kNoModule).status == 0);
    CHECK(run_sdfc("mesh " + q(s) + " -o " + q(test::temp_dir() + "/startup.stl") + " --resolution 8 -q", kNoModule).status == 0);
}

TEST_CASE("an image written without the module is an error before the work, and no file") {
    const std::string s = test::write_temp("startup_render.sdf", "sphere(1);\n");
    const std::string out = test::temp_dir() + "/startup.png";
    fs::remove(out);
    auto r = run_sdfc("render " + q(s) + " -o " + q(out) + " --width 8 --height 8", kNoModule);
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot load the image library libsdfc_image.so: not found (looked for /nonexistent/libsdfc_image.so)\n");
    CHECK_FALSE(fs::exists(out));
    auto bad = run_sdfc("render " + q(s) + " -o " + q(out) + " --width 8 --height 8", "SDFC_IMAGE_MODULE=" + q(s));
    CHECK(bad.status == 1);
    CHECK(bad.err.rfind("sdfc: error: cannot load the image library libsdfc_image.so: " + s + ": ", 0) == 0);
    // With the module found where the build puts it, the same command writes the picture.
    CHECK(run_sdfc("render " + q(s) + " -o " + q(out) + " --width 8 --height 8 -q").status == 0);
    CHECK(fs::file_size(out) > 0);
}
#endif
