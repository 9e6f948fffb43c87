// The Prospero image (render_2d: quadtree + intervals + simplified tapes) is identical,
// pixel for pixel, to brute-force evaluation of the same file.
#include <catch2/catch.hpp>

#include <filesystem>
#include <thread>
#include <vector>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"
#include "runtime/cpu/slice.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

namespace {

// threads: 0 for all cores; more than 4 runs the quadtree's second level as tasks too
// (Ctx::nested in raster2d.cpp), each making its own tape (simplify_lane).
void check_identical(const std::string& name, int w, int h, int threads = 0) {
    const fs::path path = fs::path(SDFC_SHARED_DIR) / "bench" / "vm" / name;
    if (!fs::exists(path)) {
        WARN("skipped: " << path << " is absent");
        return;
    }
    SourceManager sm;
    Scene s = load_scene(sm, path.string());
    CompiledScene cs = compile_scene(s);
    REQUIRE(cs.is_2d);
    RenderStats fast_stats, brute_stats;
    Image fast = render_2d(cs, w, h, threads, false, &fast_stats);
    Image brute = render_2d(cs, w, h, 0, true, &brute_stats);
    REQUIRE(fast.width == w);
    REQUIRE(fast.height == h);
    REQUIRE(fast.pixels.size() == brute.pixels.size());
    size_t differ = 0, white = 0;
    for (size_t i = 0; i < fast.pixels.size(); ++i) {
        differ += fast.pixels[i] != brute.pixels[i];
        white += brute.pixels[i] > 0.5f;
    }
    INFO(name << " " << w << "x" << h << ", threads " << threads << ": " << differ << " pixels differ, " << white << " white");
    REQUIRE(differ == 0);
    REQUIRE(white > 0);
    REQUIRE(fast_stats.distance_points < brute_stats.distance_points);
}

}  // namespace

TEST_CASE("render_2d: prospero.vm quadtree image equals brute force") {
    check_identical("prospero.vm", 1024, 1024);
    check_identical("prospero.vm", 1024, 1024, 1);
    check_identical("prospero.vm", 1024, 1024, 8);
}

TEST_CASE("render_2d: hi.vm and quarter.vm equal brute force, odd sizes too") {
    check_identical("hi.vm", 1024, 1024);
    check_identical("quarter.vm", 1024, 1024);
    check_identical("hi.vm", 301, 173);
    check_identical("quarter.vm", 77, 1000);
    check_identical("prospero.vm", 517, 263);
}

TEST_CASE("Raster2d: a prepared model draws the same image every time, from several threads at once") {
    const fs::path path = fs::path(SDFC_SHARED_DIR) / "bench" / "vm" / "prospero.vm";
    if (!fs::exists(path)) {
        WARN("skipped: " << path << " is absent");
        return;
    }
    SourceManager sm;
    CompiledScene cs = compile_scene(load_scene(sm, path.string()));
    RenderStats once;
    const Image expect = render_2d(cs, 512, 384, 2, false, &once);
    const Raster2d raster(cs);
    // Sizes change between renders (the kept scratch is sized by the program, not the image),
    // and each render counts only its own points.
    for (int round = 0; round < 3; ++round) {
        RenderStats st;
        CHECK(raster.render(512, 384, 2, &st).pixels == expect.pixels);
        CHECK(st.distance_points == once.distance_points);
        CHECK(raster.render(97, 203, 1).pixels == render_2d(cs, 97, 203, 1).pixels);
    }
    std::vector<Image> got(4);
    std::vector<std::thread> workers;
    for (size_t i = 0; i < got.size(); ++i) workers.emplace_back([&, i] { got[i] = raster.render(512, 384, 2); });
    for (auto& t : workers) t.join();
    for (const Image& img : got) CHECK(img.pixels == expect.pixels);
}
