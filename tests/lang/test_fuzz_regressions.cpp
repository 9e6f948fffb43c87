// Every input the fuzzer found a problem with (tests/fuzz/regressions/, one file each,
// named after what it found) runs through the fuzzer's pipeline (tests/fuzz/pipeline.hpp)
// without crashing, hanging, or any error but a CompileError. The sanitizer build (.ci/
// sanitize) replays them under ASan+UBSan too.
#include <catch2/catch.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fuzz/pipeline.hpp"

namespace fs = std::filesystem;

TEST_CASE("fuzzer regressions run through the pipeline cleanly") {
    const fs::path dir = fs::path(SDFC_SOURCE_DIR) / "tests/fuzz/regressions";
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.is_regular_file() && e.path().filename().string()[0] != '.') files.push_back(e.path());
    std::sort(files.begin(), files.end());
    CHECK(!files.empty());
    for (const auto& p : files) {
        DYNAMIC_SECTION(p.filename().string()) {
            std::ifstream in(p, std::ios::binary);
            std::stringstream ss;
            ss << in.rdbuf();
            const auto t0 = std::chrono::steady_clock::now();
            CHECK(sdfc::fuzz::run(ss.str()) == "");
            const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            CHECK(s < 60.0);  // the fuzzer's limits keep every input short; generous for sanitizer builds
        }
    }
}
