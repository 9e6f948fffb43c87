// sdfc watch (issue 15): a run now and one per save of the scene or an imported file; a
// failed run reports and leaves the last good output; --runs N stops after N runs.
#include <catch2/catch.hpp>

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;
namespace fs = std::filesystem;

namespace {

std::string q(const std::string& s) { return "'" + s + "'"; }

// Waits (up to 60 s: sanitizer builds are slow) until `path` holds `text`.
bool wait_for(const std::string& path, const std::string& text) {
    for (int i = 0; i < 600; ++i) {
        if (test::slurp(path).find(text) != std::string::npos) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
}

// Saves the way editors do: a new file renamed over the old one.
void save(const std::string& path, const std::string& text) {
    const std::string tmp = path + ".tmp";
    std::ofstream(tmp, std::ios::binary) << text;
    fs::rename(tmp, path);
}

}  // namespace

TEST_CASE("watch re-runs on every save of the scene or an import, keeping the last good output") {
    const std::string dir = test::temp_dir() + "/watch";
    fs::create_directories(dir);
    const std::string scene = dir + "/scene.sdf", lib = dir + "/lib.sdf", out = dir + "/out.png", log = dir + "/log.txt";
    const std::string pid = dir + "/pid";
    std::ofstream(lib) << "let r = 0.5;\n";
    std::ofstream(scene) << "import \"lib.sdf\";\nsphere(r);\n";
    fs::remove(out);
    const std::string cmd = "'" + std::string(SDFC_BIN_PATH) + "' watch --runs 4 --debounce 50 render " + q(scene) + " -o " + q(out) +
                            " --width 16 --height 16 -q";
    REQUIRE(std::system(("(" + cmd + " >" + q(log) + " 2>&1 </dev/null & echo $! >" + q(pid) + ")").c_str()) == 0);
    REQUIRE(wait_for(log, "sdfc watch: run 1 ok in "));
    CHECK(wait_for(log, "watching 2 files"));
    const std::string first = test::slurp(out);
    REQUIRE(!first.empty());
    save(scene, "import \"lib.sdf\";\nsphere(r;\n");  // an error: reported, nothing written
    REQUIRE(wait_for(log, "sdfc watch: run 2 failed in "));
    CHECK(test::slurp(log).find("scene.sdf:2:9: error: expected ')'") != std::string::npos);
    CHECK(test::slurp(out) == first);
    save(scene, "import \"lib.sdf\";\nsphere(r);\n");
    REQUIRE(wait_for(log, "sdfc watch: run 3 ok in "));
    CHECK(test::slurp(out) == first);  // the same scene again
    save(lib, "let r = 0.9;\n");  // an import changes
    REQUIRE(wait_for(log, "sdfc watch: run 4 ok in "));
    CHECK(test::slurp(out) != first);
    // After --runs 4 it ends by itself.
    const int p = std::atoi(test::slurp(pid).c_str());
    bool gone = false;
    for (int i = 0; i < 100 && !gone; ++i) {
        gone = ::kill(p, 0) != 0;
        if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (!gone) ::kill(p, SIGKILL);
    CHECK(gone);
}

TEST_CASE("watch's usage errors") {
    CHECK(run_sdfc("watch").err == "sdfc: error: watch needs a command: sdfc watch render SCENE -o OUT (or glsl, check, slice, mesh, eval, compile)\n");
    CHECK(run_sdfc("watch bench x.sdf").err == "sdfc: error: watch runs render, glsl, check, slice, mesh, eval or compile, not 'bench'\n");
    CHECK(run_sdfc("watch --every 2 check x.sdf").status == 2);
    CHECK(run_sdfc("watch check -").err == "sdfc: error: watch needs a scene file: standard input (-) is read once\n");
    const std::string s = test::write_temp("watch_once.sdf", "sphere(1);\n");
    auto once = run_sdfc("watch --runs 1 check " + q(s));
    CHECK(once.status == 0);
    CHECK(once.err.rfind("sdfc watch: run 1 ok in ", 0) == 0);
    CHECK(once.err.find("; watching 1 file\n") != std::string::npos);
    auto bad = run_sdfc("watch --runs 1 check " + q(test::write_temp("watch_bad.sdf", "sphere(;\n")));
    CHECK(bad.status == 1);
    CHECK(bad.err.find("sdfc watch: run 1 failed in ") != std::string::npos);
    // A command line no save can fix: watch stops (it waited for ever).
    auto wrong = run_sdfc("watch render " + q(s));
    CHECK(wrong.status == 2);
    CHECK(wrong.err == "sdfc: error: render needs -o OUT\nsdfc: error: watch stops: the command line above is wrong, and no save of the scene "
                       "can fix it\n");
    // A flag out of its range too (the scene was read before the flag was checked: it waited).
    auto width = run_sdfc("watch render " + q(s) + " -o " + q(test::temp_dir() + "/watch_w.png") + " --width 0");
    CHECK(width.status == 2);
    CHECK(width.err == "sdfc: error: --width must be from 1 to 16384, not 0\nsdfc: error: watch stops: the command line above is wrong, and no save "
                       "of the scene can fix it\n");
    // -- ends watch's options.
    CHECK(run_sdfc("watch --runs 1 -- check " + q(s)).status == 0);
}
