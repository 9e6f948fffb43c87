// Progress (issue 15): one bar for a whole batch of frames, on a terminal only.
#include <catch2/catch.hpp>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;

namespace {
std::string q(const std::string& s) { return "'" + s + "'"; }
}  // namespace

TEST_CASE("a batch of frames has one bar with the frame count, on a terminal only") {
    const std::string s = test::write_temp("progress.sdf", "rotate(y = 30 * time) box([1, 0.5, 0.5]);\n");
    const std::string out = test::temp_dir() + "/progress_{frame}.png";
    const std::string args = "render " + q(s) + " -o " + q(out) + " --frames 0:2 --fps 4 --width 32 --height 24";
    // Not a terminal: the summary lines only.
    auto plain = run_sdfc(args, "SDFC_PROGRESS_AFTER=0");
    REQUIRE(plain.status == 0);
    CHECK(plain.err.find('[') == std::string::npos);
    // A terminal (script(1) gives the command one): the bar between and during the frames.
    if (std::system("command -v script >/dev/null 2>&1") != 0) {
        WARN("script(1) is not installed: the terminal half is skipped");
        return;
    }
    const std::string log = test::temp_dir() + "/progress_tty.txt";
    const std::string cmd = "SDFC_PROGRESS_AFTER=0 script -qefc \"'" + std::string(SDFC_BIN_PATH) + "' " + args + "\" /dev/null >" + q(log) +
                            " 2>&1 </dev/null";
    REQUIRE(std::system(cmd.c_str()) == 0);
    const std::string tty = test::slurp(log);
    CHECK(tty.find("]  33% frame 2/3 ") != std::string::npos);
    CHECK(tty.find("]  66% frame 3/3 ") != std::string::npos);
    CHECK(tty.find("sdfc: wrote " + test::temp_dir() + "/progress_2.png (32x24, ") != std::string::npos);
}
