// The Prospero image (render_2d: quadtree + intervals + simplified tapes) is identical,
// pixel for pixel, to brute-force evaluation of the same file.
#include <catch2/catch.hpp>

#include <random>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"
#include "runtime/cpu/slice.hpp"
#include "shared_models.hpp"

using namespace sdfc;

namespace {

// threads: 0 for all cores; more than 4 runs the quadtree's second level as tasks too
// (Ctx::nested in raster2d.cpp), each making its own tape (simplify_lane).
void check_identical(const std::string& name, int w, int h, int threads = 0) {
    const auto model = test::shared_model(name);
    if (!model) return;
    const CompiledScene& cs = model->cs;
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

// A Prospero-like model made here (no shared files): a union of discs, each cut by a half
// plane, minus a few rings, with a wavy edge (sin, exp) on one disc. Its leaves run through
// the sweep, with choices decided per leaf and copies of winners.
std::string generated_model(int discs) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), r(0.02f, 0.25f);
    std::string m = "x var-x\ny var-y\n";
    std::string acc;
    for (int i = 0; i < discs; ++i) {
        m += fmt::format("cx{0} const {1}\ncy{0} const {2}\nr{0} const {3}\nk{0} const {4}\n", i, u(rng), u(rng), r(rng), u(rng));
        m += fmt::format("dx{0} sub x cx{0}\ndy{0} sub y cy{0}\nsx{0} square dx{0}\nsy{0} square dy{0}\n", i);
        m += fmt::format("s{0} add sx{0} sy{0}\nl{0} sqrt s{0}\nd{0} sub l{0} r{0}\n", i);
        m += fmt::format("h{0} sub dy{0} k{0}\nc{0} max d{0} h{0}\n", i);  // cut by the half plane y > cy + k
        if (i % 17 == 3) m += fmt::format("w{0} sin dx{0}\ne{0} exp w{0}\nq{0} mul e{0} r{0}\nc{0}b min c{0} q{0}\n", i);
        const std::string c = i % 17 == 3 ? fmt::format("c{}b", i) : fmt::format("c{}", i);
        if (acc.empty()) {
            acc = c;
        } else {
            m += fmt::format("u{0} min {1} {2}\n", i, acc, c);
            acc = fmt::format("u{}", i);
        }
        if (i % 9 == 8) {  // a ring taken out: max(acc, -(|d| - 0.01))
            m += fmt::format("a{0} abs d{0}\nt{0} const 0.01\nb{0} sub a{0} t{0}\nn{0} neg b{0}\nv{0} max {1} n{0}\n", i, acc);
            acc = fmt::format("v{}", i);
        }
    }
    return m;
}

TEST_CASE("render_2d: a generated model of 300 cut discs equals brute force, at several sizes and thread counts") {
    SourceManager sm;
    const SourceFile& f = sm.add("generated.vm", generated_model(300));
    CompiledScene cs = compile_scene(load_vm(sm, f));
    REQUIRE(cs.is_2d);
    for (auto [w, h, threads] : {std::tuple{1024, 1024, 2}, {1024, 1024, 1}, {301, 173, 2}, {77, 1000, 8}, {8, 8, 1}, {9, 700, 2}}) {
        RenderStats fast_stats, brute_stats;
        const Image fast = render_2d(cs, w, h, threads, false, &fast_stats);
        const Image brute = render_2d(cs, w, h, 0, true, &brute_stats);
        REQUIRE(fast.pixels.size() == brute.pixels.size());
        size_t differ = 0, white = 0;
        for (size_t i = 0; i < fast.pixels.size(); ++i) {
            differ += fast.pixels[i] != brute.pixels[i];
            white += brute.pixels[i] > 0.5f;
        }
        INFO(w << "x" << h << ", threads " << threads << ": " << differ << " pixels differ, " << white << " white");
        CHECK(differ == 0);
        CHECK(white > 0);
        CHECK(white < fast.pixels.size());
        if (w * h > 10000) CHECK(fast_stats.distance_points < brute_stats.distance_points);
    }
}

// max(ln x, 0) is NaN where x < 0, and max(x, NaN) is x there: inside. A sign-only
// decision once replaced max(ln x, 0) by its 0 where ln x may be NaN ("never < 0" for the op
// itself), and max(x, 0) is not inside: the left half came out empty.
TEST_CASE("render_2d: a sign decision keeps a NaN operand's NaN (max(x, max(ln x, 0)))") {
    SourceManager sm;
    const SourceFile& f = sm.add("nan.vm", "x var-x\nz const 0\nl ln x\nm max l z\no max x m\n");
    const CompiledScene cs = compile_scene(load_vm(sm, f));
    for (auto [w, h] : {std::pair{16, 1}, {64, 64}, {9, 700}}) {
        const Image fast = render_2d(cs, w, h, 1), brute = render_2d(cs, w, h, 1, true);
        INFO(w << "x" << h);
        CHECK(fast.pixels == brute.pixels);
        CHECK(fast.at(0, h - 1, 0) == 1.0f);  // x = -1: inside
        CHECK(fast.at(w - 1, 0, 0) == 0.0f);  // x = 1: outside
    }
}

TEST_CASE("Raster2d: a prepared model draws the same image every time, from several threads at once") {
    const auto model = test::shared_model("prospero.vm");
    if (!model) return;
    const CompiledScene& cs = model->cs;
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
