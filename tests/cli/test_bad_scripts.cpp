// The bad-script corpus end to end: `sdfc check` on each file of tests/bad/ exits 1 and
// prints the expected diagnostic first (see tests/bad_corpus.hpp); `sdfc render` writes
// nothing.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>

#include "bad_corpus.hpp"
#include "run.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

namespace {
std::string joined(const std::vector<std::string>& args) {
    std::string s;
    for (const auto& a : args) s += " '" + a + "'";
    return s;
}
}  // namespace

TEST_CASE("sdfc check reports each bad script's expected error, exit status 1") {
    for (const auto& c : test::bad_cases()) {
        DYNAMIC_SECTION(c.name) {
            auto r = test::run_sdfc("check '" + c.path + "'" + joined(c.args));
            std::string err = test::relative_paths(r.err);
            INFO(err);
            CHECK(r.status == 1);
            CHECK(r.out.empty());
            CHECK(err.substr(0, err.find('\n')) == c.expect);
        }
    }
}

TEST_CASE("sdfc render of a bad script writes no image and leaves no temporary file") {
    const std::string dir = test::temp_dir() + "/bad-render";
    fs::create_directories(dir);
    // A few kinds (each case is a process start): parse, interpret, limit, import, compile.
    const std::vector<std::string> some{"syntax_missing_semicolon.sdf", "nan_division_by_zero.sdf", "limit_shapes.sdf",
                                        "import_cycle.sdf", "inf_gyroid_period.sdf", "camera_position_is_target.sdf"};
    for (const auto& c : test::bad_cases()) {
        if (std::find(some.begin(), some.end(), c.name) == some.end()) continue;
        DYNAMIC_SECTION(c.name) {
            const std::string out = dir + "/out.png";
            auto r = test::run_sdfc("render '" + c.path + "' -o '" + out + "' --width 8 --height 8 --quiet" + joined(c.args));
            CHECK(r.status == 1);
            CHECK(fs::is_empty(dir));
        }
    }
}
