// Unions of many bounded shapes are lowered as a k-d min tree (compiler/scene/lower.cpp,
// lower_union_spatial): the same distances as the script's chain, and much shorter
// programs once interval arithmetic simplifies them over a small box.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <string>

#include "runtime/eval/interval.hpp"
#include "support.hpp"

using namespace sdfc;

namespace {

// k x k spheres on a 16 x 16 square, radius 0.35 of the cell (bench/run's grid);
// `far_floor`: in one union block with a plane far below, an unbounded child, so the union
// stays a chain in script order (and the plane is too far to bound anything near the
// spheres). (A plane beside the loop at the top level would not do: the loop's iterations
// are then a union of their own, which gets the tree.)
std::string grid(int k, bool far_floor) {
    return std::string(far_floor ? "union {\nplane([0, 1, 0], -100);\n" : "") + "let c = 16 / " + std::to_string(k) +
           ";\nfor (i = [0 : " + std::to_string(k - 1) + "], j = [0 : " + std::to_string(k - 1) +
           "]) translate([(i + 0.5) * c - 8, 0.35 * c, (j + 0.5) * c - 8]) sphere(0.35 * c);\n" + (far_floor ? "}\n" : "");
}

// Length of the distance program simplified for the cube of side s around (x, y, z).
size_t tape_in_box(const CompiledScene& cs, float x, float y, float z, float s) {
    Tape t = Tape::from(cs.distance, 0);
    t.link();
    const float xlo = x - s / 2, xhi = x + s / 2, ylo = y - s / 2, yhi = y + s / 2, zlo = z - s / 2, zhi = z + s / 2;
    IntervalEvaluator iv(t.num_regs, t.choices);
    iv.eval(t, &xlo, &xhi, &ylo, &yhi, &zlo, &zhi, 1);
    Tape out;
    SimplifyScratch sc;
    simplify(t, iv.choices(), iv.stride(), 0, out, sc);
    return out.code.size();
}

}  // namespace

TEST_CASE("spatial union: the distance is the minimum over the spheres, exactly", "[union][interval]") {
    const int k = 12;
    auto c = test::compile_text(grid(k, false));
    const float cell = 16.0f / k;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-9.0f, 9.0f);
    for (int n = 0; n < 500; ++n) {
        const float x = u(rng), y = 0.25f * u(rng), z = u(rng);
        float best = INFINITY;
        for (int i = 0; i < k; ++i)
            for (int j = 0; j < k; ++j) {
                const float cx = (i + 0.5f) * cell - 8, cy = 0.35f * cell, cz = (j + 0.5f) * cell - 8;
                best = std::min(best, std::sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz)) - 0.35f * cell);
            }
        INFO("at " << x << ", " << y << ", " << z);
        CHECK(test::dist(c->cs, x, y, z) == Approx(best).margin(1e-5));
    }
}

TEST_CASE("spatial union: a small box keeps a few spheres of a 100 x 100 grid", "[union][interval]") {
    auto c = test::compile_text(grid(100, false));
    const size_t full = c->cs.distance.code.size();
    REQUIRE(full > 30000);
    // A box of 3 x 3 cells next to the sphere nearest the centre: a few dozen spheres.
    const size_t len = tape_in_box(c->cs, 0.08f, 0.06f, 0.08f, 0.5f);
    INFO(len << " of " << full);
    CHECK(len < full / 40);
    // The script's chain keeps far more: every sphere about as far as the running minimum.
    auto chain = test::compile_text(grid(100, true));
    const size_t chain_len = tape_in_box(chain->cs, 0.08f, 0.06f, 0.08f, 0.5f);
    INFO("chain " << chain_len);
    CHECK(chain_len > 4 * len);
}
