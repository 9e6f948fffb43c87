// Golden listings: `sdfc compile --emit ast|ir|bytecode` for every example, diffed against
// tests/golden/. After an intended change, regenerate with SDFC_UPDATE_GOLDEN=1 and review
// the diff like code.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "run.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

TEST_CASE("golden listings of every example") {
    bool update = std::getenv("SDFC_UPDATE_GOLDEN") != nullptr;
    fs::path golden = fs::path(SDFC_SOURCE_DIR) / "tests" / "golden";
    std::vector<fs::path> examples;
    for (const auto& e : fs::directory_iterator(fs::path(SDFC_SOURCE_DIR) / "examples"))
        if (e.path().extension() == ".sdf") examples.push_back(e.path());
    std::sort(examples.begin(), examples.end());
    REQUIRE(!examples.empty());
    for (const fs::path& ex : examples) {
        for (const char* emit : {"ast", "ir", "bytecode"}) {
            // Run from the examples folder with a relative path so listings don't embed this machine's paths.
            auto r = test::run_sdfc("compile '" + ex.string() + "' --emit " + emit);
            REQUIRE(r.status == 0);
            std::string text = r.out;
            // Paths in listings are the command-line path; make them relative for stability.
            for (size_t p; (p = text.find(ex.parent_path().string() + "/")) != std::string::npos;)
                text.erase(p, ex.parent_path().string().size() + 1);
            fs::path file = golden / (ex.stem().string() + "." + emit + ".txt");
            if (update) {
                std::ofstream(file, std::ios::binary) << text;
                continue;
            }
            INFO("golden file " << file << " (regenerate with SDFC_UPDATE_GOLDEN=1 after an intended change)");
            REQUIRE(fs::exists(file));
            CHECK(text == test::slurp(file.string()));
        }
    }
}
