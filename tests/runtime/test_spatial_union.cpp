// Unions of many bounded shapes are lowered as a k-d min tree (compiler/scene/lower.cpp,
// lower_union_spatial): the same distances as the script's chain, and much shorter
// programs once interval arithmetic simplifies them over a small box.
#include <catch2/catch.hpp>

#include <bit>
#include <cmath>
#include <random>
#include <string>

#include "runtime/eval/interval.hpp"
#include "runtime/eval/vm.hpp"
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

// The distance program simplified for the cube of side s around (x, y, z); `chains`: with
// the union pruned as a whole (Tape::mark_min_chains, as the tape tree does).
Tape tape_for_box(const CompiledScene& cs, float x, float y, float z, float s, bool chains = false) {
    Tape t = Tape::from(cs.distance, 0);
    t.link();
    if (chains) t.mark_min_chains();
    const float xlo = x - s / 2, xhi = x + s / 2, ylo = y - s / 2, yhi = y + s / 2, zlo = z - s / 2, zhi = z + s / 2;
    IntervalEvaluator iv(t.num_regs, t.choices);
    iv.keep_chains(chains);
    iv.eval(t, &xlo, &xhi, &ylo, &yhi, &zlo, &zhi, 1);
    iv.prune_min_chains(t, 1);
    Tape out;
    SimplifyScratch sc;
    simplify(t, iv.choices(), iv.stride(), 0, out, sc);
    return out;
}
size_t tape_in_box(const CompiledScene& cs, float x, float y, float z, float s) { return tape_for_box(cs, x, y, z, s).code.size(); }

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
    REQUIRE(full > 20000);  // (10,000 spheres: a length3_i, a min and shared add_i each, and the guards)
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

TEST_CASE("spatial union: the batch VM skips a guarded region only when every point of the batch is far from its box",
          "[union][guard]") {
    // A region that lies (its value 0.5 is below its box's distance) shows whether it ran:
    // min(1, region) is 0.5 when it ran, 1 when it was skipped.
    auto program = [](float threshold) {
        Program p;
        auto add = [&](Op op, uint16_t out, uint16_t a = 0, uint16_t b = 0, float k = 0.0f) {
            Instr in{op};
            in.out = out, in.a = a, in.b = b, in.k = k;
            p.code.push_back(in);
        };
        add(Op::VarX, 0), add(Op::VarY, 1), add(Op::VarZ, 2);
        add(Op::Const, 3, 0, 0, threshold);  // the union's distance so far
        add(Op::Guard, 4, 3, 0, 0.0f);       // guards[0]
        add(Op::Const, 4, 0, 0, 0.5f);       // the region
        add(Op::Min, 5, 3, 4);
        p.guards.push_back(test::cube_guard(10.0f, 11.0f, 6));
        p.locs.resize(p.code.size());
        p.num_regs = 6;
        p.outputs = {5};
        p.output_names = {"out"};
        return p;
    };
    const Program p = program(1.0f);
    Evaluator ev(p);
    float xs[kBatch], ys[kBatch], zs[kBatch];
    for (int i = 0; i < kBatch; ++i) xs[i] = ys[i] = zs[i] = 0.01f * float(i);  // 15.6 .. 17.3 from the box
    ev.eval(xs, ys, zs, kBatch);
    for (int i = 0; i < kBatch; ++i) CHECK(ev.output(0)[i] == 1.0f);  // skipped
    xs[40] = 9.5f, ys[40] = 10.5f, zs[40] = 10.5f;  // one point 0.5 from the box: within 1
    ev.eval(xs, ys, zs, kBatch);
    for (int i = 0; i < kBatch; ++i) CHECK(ev.output(0)[i] == 0.5f);  // ran, for all
    xs[40] = 8.95f;  // 1.05 from the box: beyond the threshold and its rounding margin (~0.003)
    ev.eval(xs, ys, zs, kBatch);
    for (int i = 0; i < kBatch; ++i) CHECK(ev.output(0)[i] == 1.0f);
    // Tapes without the guard table (shortened tapes) always run through.
    TapeView v = p.view();
    v.guards = nullptr;
    ev.eval(v, xs, ys, zs, kBatch);
    for (int i = 0; i < kBatch; ++i) CHECK(ev.output(v)[i] == 0.5f);
    // Huge: 2e19 from the box, the threshold 3e19; squared, both overflow to +inf.
    const Program huge = program(3e19f);
    Evaluator eh(huge);
    for (int i = 0; i < kBatch; ++i) xs[i] = -2e19f, ys[i] = zs[i] = 10.5f;
    eh.eval(xs, ys, zs, kBatch);
    for (int i = 0; i < kBatch; ++i) CHECK(eh.output(0)[i] == 0.5f);  // ran
}

TEST_CASE("spatial union: pruned as a whole, a small box keeps the spheres near it, with the same floats", "[union][interval]") {
    auto c = test::compile_text(grid(100, false));
    const size_t full = c->cs.distance.code.size();
    const float x = 0.08f, y = 0.06f, z = 0.08f, s = 0.5f;
    const Tape alone = tape_for_box(c->cs, x, y, z, s), whole = tape_for_box(c->cs, x, y, z, s, true);
    INFO(whole.code.size() << " against " << alone.code.size() << " of " << full);
    // Each min against the nearest sphere anywhere in the union, not only its sibling's.
    CHECK(whole.code.size() * 2 < alone.code.size());
    Evaluator ev(c->cs.distance);
    BatchVM vm(1);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    float xs[kBatch], ys[kBatch], zs[kBatch];
    for (int i = 0; i < kBatch; ++i) xs[i] = x + s * u(rng), ys[i] = y + s * u(rng), zs[i] = z + s * u(rng);
    ev.eval(xs, ys, zs, kBatch);
    vm.eval(whole.view(), xs, ys, zs, kBatch);
    for (int i = 0; i < kBatch; ++i) CHECK(std::bit_cast<uint32_t>(vm.output(whole.view())[i]) == std::bit_cast<uint32_t>(ev.output(0)[i]));
}

TEST_CASE("a long smooth union drops its far operands whole from a pruned tape", "[union][interval]") {
    // 10 x 10 spheres 1.6 apart (radius 0.56), blended by 0.1: around one sphere's centre
    // every other operand is proved more than k away. Each used to leave 6 instructions
    // computing 0 (the blend's h); now the blend is a select and goes with its operand.
    const std::string src = "smooth_union(0.1) {\n" + grid(10, false) + "}\n";
    auto c = test::compile_text(src);
    const float cell = 1.6f;
    REQUIRE(c->cs.distance.code.size() > 1000);
    for (int i : {0, 3, 9})
        for (int j : {0, 5, 9}) {
            INFO("sphere " << i << ", " << j);
            const float x = (float(i) + 0.5f) * cell - 8, y = 0.35f * cell, z = (float(j) + 0.5f) * cell - 8;
            const Tape t = tape_for_box(c->cs, x, y, z, 0.4f);
            CHECK(t.code.size() < 30);
            Evaluator full(c->cs.distance);
            BatchVM vm(64);
            const float px[1] = {x + 0.1f}, py[1] = {y}, pz[1] = {z - 0.05f};
            vm.eval(t.view(), px, py, pz, 1, 0.0f);
            CHECK(vm.output(t.view())[0] == full.eval1(px[0], py[0], pz[0], 0.0f));
        }
}
