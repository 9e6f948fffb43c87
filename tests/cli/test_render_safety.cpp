// Rendering never writes NaN pixels, whatever the field computes, and never leaves a
// partial output: a render killed with SIGKILL leaves the target absent or as it was.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include "run.hpp"
#include "support.hpp"
#include "runtime/io/image.hpp"

using namespace sdfc;
using test::run_sdfc;
namespace fs = std::filesystem;

namespace {

std::string temp_files_of(const std::string& dir) {
    std::string names;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().filename().string().find(".tmp-") != std::string::npos) names += e.path().filename().string() + " ";
    return names;
}

// `sdfc ARGS...` started in the background (stdout and stderr to /dev/null).
pid_t spawn_sdfc(const std::vector<std::string>& args) {
    const char* bin = std::getenv("SDFC_BIN");
    std::string exe = bin ? bin : SDFC_BIN_PATH;
    std::vector<char*> argv{exe.data()};
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = ::fork();
    if (pid == 0) {
        FILE* null = std::fopen("/dev/null", "w");
        if (null) {
            ::dup2(fileno(null), 1);
            ::dup2(fileno(null), 2);
        }
        ::execv(exe.c_str(), argv.data());
        ::_exit(127);
    }
    return pid;
}

}  // namespace

TEST_CASE("fields that compute NaN or infinity render without NaN pixels, AOVs included") {
    const std::vector<std::pair<std::string, std::string>> fields{
        {"sqrt", "field (p) -> sqrt(p.x) - 0.5"},                    // NaN on half the space
        {"reciprocal", "field (p) -> 1 / p.x"},                     // infinite on a plane
        {"log", "field (p) -> log(abs(p.y)) + 0.5"},                // -inf on a plane
        {"nan_everywhere", "field (p) -> sqrt(-1 - abs(p.x))"},
        {"inf_everywhere", "field (p) -> exp(100 + abs(p.x))"},
        {"minus_inf_everywhere", "field (p) -> -exp(100 + abs(p.x))"},
        {"overflow", "field (p) -> length(p) * 1e30 * 1e30 - 1"},
        {"nan_in_csg", "smooth_union(0.5) { sphere(1); field (p) -> sqrt(p.y); }"},
    };
    for (const auto& [name, body] : fields) {
        DYNAMIC_SECTION(name) {
            std::string s = test::write_temp("nan_" + name + ".sdf",
                                             "camera(position = [0, 0.3, 4]);\nlight(position = [2, 3, 4], radius = 0.2);\n" + body + ";\n");
            std::string out = test::temp_dir() + "/nan_" + name + ".exr";
            auto r = run_sdfc("render '" + s + "' -o '" + out + "' --width 24 --height 16 --samples 2 --aov depth,normal,steps --quiet");
            INFO(r.err);
            REQUIRE(r.status == 0);
            Image img = read_image(out);
            CHECK(img.width == 24);
            CHECK(img.aovs.size() == 3);
            CHECK(test::all_finite(img));
        }
    }
}

TEST_CASE("a render killed with SIGKILL never leaves a partial output") {
    // A fast scene with a large, slow-to-write output: the kill lands while rendering or
    // while writing the temporary file. An interrupted run may leave that temporary file
    // (.NAME.tmp-PID-N.EXT, nothing can remove it after SIGKILL); never a partial OUT.
    const std::string dir = test::temp_dir() + "/kill";
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::string s = test::write_temp("kill.sdf", "camera(position = [0, 0, 4]);\nsphere(1);\n");
    const std::string out = dir + "/out.exr";
    const std::vector<std::string> args{"render", s, "-o", out, "--width", "3000", "--height", "2000", "--samples", "1",
                                        "--aov", "depth,normal,steps", "--quiet"};
    // An existing output, to see that it is replaced only by a complete image.
    std::string before = test::write_temp("kill_before.sdf", "sphere(1);\n");
    REQUIRE(run_sdfc("render '" + before + "' -o '" + out + "' --width 16 --height 8 --quiet").status == 0);
    const std::string old_bytes = test::slurp(out);

    int killed_while_writing = 0, killed_before_writing = 0;
    for (int trial = 0; trial < 6; ++trial) {
        INFO("trial " << trial);
        pid_t pid = spawn_sdfc(args);
        REQUIRE(pid > 0);
        // Odd trials: kill as soon as the temporary file appears; even trials: after a delay
        // that grows, so that some land mid-render.
        const auto t0 = std::chrono::steady_clock::now();
        const auto delay = std::chrono::milliseconds(100 * (trial + 1));
        bool exited = false;
        for (;;) {
            int st = 0;
            if (::waitpid(pid, &st, WNOHANG) == pid) { exited = true; break; }
            bool writing = !temp_files_of(dir).empty();
            if ((trial % 2 == 1 && writing) || (trial % 2 == 0 && std::chrono::steady_clock::now() - t0 > delay)) {
                (writing ? killed_while_writing : killed_before_writing) += 1;
                break;
            }
            std::this_thread::sleep_for(std::chrono::microseconds(500));
        }
        if (!exited) {
            ::kill(pid, SIGKILL);
            int st = 0;
            REQUIRE(::waitpid(pid, &st, 0) == pid);
        }
        // OUT is the old file, byte for byte, or a complete new image.
        REQUIRE(fs::exists(out));
        const std::string now = test::slurp(out);
        if (now != old_bytes) {
            Image img = read_image(out);
            CHECK(img.width == 3000);
            CHECK(img.height == 2000);
            CHECK(img.aovs.size() == 3);
            std::ofstream(out, std::ios::binary) << old_bytes;  // back to the old one
        }
        for (const auto& e : fs::directory_iterator(dir))
            if (e.path().filename().string().find(".tmp-") != std::string::npos) fs::remove(e.path());
    }
    CHECK(killed_while_writing + killed_before_writing > 0);
    WARN("killed while writing: " << killed_while_writing << ", before: " << killed_before_writing);

    // Without an existing output, a killed run leaves none.
    fs::remove(out);
    pid_t pid = spawn_sdfc(args);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ::kill(pid, SIGKILL);
    int st = 0;
    ::waitpid(pid, &st, 0);
    if (WIFSIGNALED(st)) CHECK(!fs::exists(out));
}

TEST_CASE("a main picture that fails to write takes its new side files away, merge refuses a device, slice refuses rows past 16384") {
    const std::string dir = test::temp_dir() + "/sides";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string s = test::write_temp("sides.sdf", "sphere(1);\n");
    // jp2 does not read back at 8 x 8: the depth side file, written first, must go too.
    auto r = run_sdfc("render '" + s + "' -o '" + dir + "/x.jp2' --aov depth --width 8 --height 8 --quiet");
    CHECK(r.status == 1);
    CHECK(r.err.rfind("sdfc: error: cannot write '" + dir + "/x.jp2': ", 0) == 0);
    CHECK(!fs::exists(dir + "/x.depth.png"));
    CHECK(!fs::exists(dir + "/x.jp2"));
    // A format that takes no RGB is found before the render (on a small picture), not after.
    r = run_sdfc("render '" + s + "' -o '" + dir + "/y.zfile' --width 8 --height 8 --quiet");
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot write '" + dir + "/y.zfile': Zfile only supports 1 channel, not 3\n");
    CHECK(fs::is_empty(dir));
    // A band from /dev/zero never ends: refused before it is read.
    REQUIRE(run_sdfc("render '" + s + "' -o '" + dir + "/p1.exr' --tiles 1/2 --width 64 --height 64 --quiet").status == 0);
    r = run_sdfc("merge /dev/zero '" + dir + "/p1.exr' -o '" + dir + "/m.png'");
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot read '/dev/zero': not a regular file\n");
    // A range 1e-30 wide and 2 tall asks for more rows than --height allows: said, not an int
    // overflow's one row, nor 16384 rows silently stretched; with --height it is drawn.
    r = run_sdfc("slice '" + s + "' --axis x --at 0 -o '" + dir + "/s.exr' --width 4 --range=-1e-30,1e-30,-1,1");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: --range is 1e+30 times as tall as wide: 4e+30 rows at --width 4, over 16384 (give "
                   "--height: the picture then shows more of the plane across)\n");
    REQUIRE(run_sdfc("slice '" + s + "' --axis x --at 0 -o '" + dir + "/s.exr' --width 4 --height 16 --range=-1e-30,1e-30,-1,1").status == 0);
    CHECK(read_image(dir + "/s.exr").height == 16);
    r = run_sdfc("slice '" + s + "' --axis x --at 0 -o '" + dir + "/s.exr' --range=-3e38,3e38,-3e38,3e38");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: --range must lie within 1e15 of the origin\n");
}
