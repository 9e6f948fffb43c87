// Tape simplification (runtime/eval/interval.hpp) on a scene of several shapes: simplified
// tapes, and tapes simplified again from them, compute the same floats as their parent
// inside the box. (Every opcode, shape and example through the interval evaluators and the
// simplifiers: tests/conformance/test_boxes.cpp.)
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"
#include "runtime/eval/interval.hpp"
#include "runtime/eval/vm.hpp"
#include "support.hpp"

using namespace sdfc;

namespace {

bool unknown(Interval r) { return std::isnan(r.lo) || std::isnan(r.hi); }

bool inside(float v, Interval r) {
    if (unknown(r)) return true;  // unknown: anything
    if (std::isnan(v)) return false;  // a known interval promises no NaN
    return r.lo <= v && v <= r.hi;
}

}  // namespace

TEST_CASE("simplified tapes compute the same floats as the full tape inside their box") {
    auto c = test::compile_text(R"(
        union() {
            translate([0.5, 0, 0]) sphere(0.3);
            translate([-0.5, 0.2, 0]) box([0.2, 0.3, 0.2]);
            smooth_union(0.1) { translate([0, -0.5, 0]) torus(0.3, 0.1); translate([0, 0.5, 0.1]) sphere(0.2); }
        }
    )");
    const Program& prog = c->cs.distance;
    const Tape full = Tape::from(prog);
    IntervalEvaluator iv(full.num_regs, full.choices);
    SimplifyScratch ss;
    Evaluator ev(prog);
    BatchVM vm(1);  // grows to the tapes it runs
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.2f, 1.2f), sz(0.01f, 0.6f);
    size_t shorter = 0;
    for (int trial = 0; trial < 200; ++trial) {
        float lo[3][kIvLanes], hi[3][kIvLanes];
        for (int l = 0; l < kIvLanes; ++l)
            for (int a = 0; a < 3; ++a) {
                lo[a][l] = u(rng);
                hi[a][l] = lo[a][l] + sz(rng);
            }
        iv.eval(full, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], kIvLanes);
        for (int l = 0; l < kIvLanes; l += 7) {
            Tape t;
            simplify(full, iv.choices(), iv.stride(), l, t, ss);
            REQUIRE(t.num_regs <= prog.num_regs);
            shorter += t.code.size() < full.code.size();
            float xs[kBatch], ys[kBatch], zs[kBatch];
            for (int i = 0; i < kBatch; ++i) {
                auto in = [&](int a) { return i == 0 ? lo[a][l] : i == 1 ? hi[a][l] : lo[a][l] + (hi[a][l] - lo[a][l]) * float(rng() % 1001) / 1000.0f; };
                xs[i] = in(0), ys[i] = in(1), zs[i] = in(2);
            }
            ev.eval(xs, ys, zs, kBatch);
            float want[kBatch];
            for (int i = 0; i < kBatch; ++i) want[i] = ev.output(0)[i];
            const Interval r = iv.result(l);
            vm.eval(t.view(), xs, ys, zs, kBatch);
            for (int i = 0; i < kBatch; ++i) {
                REQUIRE(std::bit_cast<uint32_t>(vm.output(t.view())[i]) == std::bit_cast<uint32_t>(want[i]));
                REQUIRE(inside(want[i], r));
            }
        }
    }
    REQUIRE(shorter > 0);
}

TEST_CASE("simplify_batch: compact tapes and traces compute the full tape's floats in their boxes") {
    auto c = test::compile_text(R"(
        union() {
            translate([0.5, 0, 0]) sphere(0.3);
            translate([-0.5, 0.2, 0]) box([0.2, 0.3, 0.2]);
            smooth_union(0.1) { translate([0, -0.5, 0]) torus(0.3, 0.1); translate([0, 0.5, 0.1]) sphere(0.2); }
            translate([0.3, 0.6, -0.2]) rotate([10, 20, 30]) cylinder(0.4, 0.1);
        }
    )");
    const Program& prog = c->cs.distance;
    const Tape full = Tape::from(prog);
    IntervalEvaluator iv(full.num_regs, full.choices), iv2(full.num_regs, full.choices);
    BatchScratch bs, bs2;
    Evaluator ev(prog);
    BatchVM vm(1);  // runs the children through their views (and grows to fit them)
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.2f, 1.2f), sz(0.01f, 0.8f);
    size_t shorter = 0;
    for (int trial = 0; trial < 40; ++trial) {
        float lo[3][kIvLanes], hi[3][kIvLanes];
        for (int l = 0; l < kIvLanes; ++l)
            for (int a = 0; a < 3; ++a) {
                lo[a][l] = u(rng);
                hi[a][l] = lo[a][l] + sz(rng);
            }
        const int n = 1 + int(rng() % kIvLanes);
        iv.eval(full, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], n);
        const uint64_t lanes = n == 64 ? ~uint64_t(0) : ((uint64_t(1) << n) - 1);
        for (bool compact : {true, false}) {
            simplify_batch(full, iv.choices(), iv.stride(), lanes, bs, compact);
            for (int l = 0; l < n; ++l) {
                shorter += bs.len[size_t(l)] < full.code.size();
                float xs[kBatch], ys[kBatch], zs[kBatch];
                for (int i = 0; i < kBatch; ++i) {
                    auto in = [&](int a) { return i == 0 ? lo[a][l] : i == 1 ? hi[a][l] : lo[a][l] + (hi[a][l] - lo[a][l]) * float(rng() % 1001) / 1000.0f; };
                    xs[i] = in(0), ys[i] = in(1), zs[i] = in(2);
                }
                ev.eval(xs, ys, zs, kBatch);
                float want[kBatch];
                for (int i = 0; i < kBatch; ++i) want[i] = ev.output(0)[i];
                vm.eval(bs.view(l), xs, ys, zs, kBatch);
                for (int i = 0; i < kBatch; ++i)
                    REQUIRE(std::bit_cast<uint32_t>(vm.output(bs.view(l))[i]) == std::bit_cast<uint32_t>(want[i]));
                if (!compact || l % 9 != 0) continue;
                // A compact child simplifies further, over sub-boxes of its box.
                Tape child;
                child.assign(bs.code(l), bs.len[size_t(l)], bs.out[size_t(l)], bs.regs[size_t(l)]);
                child.link();
                float sl[3][kIvLanes], sh[3][kIvLanes];
                for (int k = 0; k < 4; ++k)
                    for (int a = 0; a < 3; ++a) {
                        const float mid = 0.5f * (lo[a][l] + hi[a][l]);
                        sl[a][k] = (k >> (a % 2)) & 1 ? mid : lo[a][l];
                        sh[a][k] = (k >> (a % 2)) & 1 ? hi[a][l] : mid;
                    }
                iv2.eval(child, sl[0], sh[0], sl[1], sh[1], sl[2], sh[2], 4);
                simplify_batch(child, iv2.choices(), iv2.stride(), 0xF, bs2, true);
                for (int k = 0; k < 4; ++k) {
                    for (int i = 0; i < kBatch; ++i) {
                        auto in = [&](int a) { return sl[a][k] + (sh[a][k] - sl[a][k]) * float(rng() % 1001) / 1000.0f; };
                        xs[i] = in(0), ys[i] = in(1), zs[i] = in(2);
                    }
                    ev.eval(xs, ys, zs, kBatch);
                    for (int i = 0; i < kBatch; ++i) want[i] = ev.output(0)[i];
                    vm.eval(bs2.view(k), xs, ys, zs, kBatch);
                    for (int i = 0; i < kBatch; ++i)
                        REQUIRE(std::bit_cast<uint32_t>(vm.output(bs2.view(k))[i]) == std::bit_cast<uint32_t>(want[i]));
                }
            }
        }
    }
    REQUIRE(shorter > 0);
}

TEST_CASE("sign-only min/max (a 2D image's tape) are decided by sign where the operands' intervals overlap") {
    // One op over x and y in a box: the choice the interval evaluator records, with and
    // without Tape::mark_sign_only.
    auto choice = [](Op op, float k, Interval x, Interval y, bool sign_only) {
        Tape t = Tape::from(test::single_op_program(op, k));
        if (sign_only) t.mark_sign_only();
        IntervalEvaluator iv(t.num_regs, t.choices);
        const float z = 0.0f;
        iv.eval(t, &x.lo, &x.hi, &y.lo, &y.hi, &z, &z, 1);
        return iv.choices()[0];
    };
    const float nan = std::nanf("");
    const Interval pos{0.5f, 2.0f}, neg{-2.0f, -0.5f}, across{-1.0f, 1.0f}, unknown{nan, nan};
    // Overlapping values: the value rule keeps both sides.
    CHECK(choice(Op::Min, 0, pos, across, false) == kChoiceBoth);
    CHECK(choice(Op::Max, 0, neg, across, false) == kChoiceBoth);
    // min(a, b) < 0 is b < 0 where a >= 0; max(a, b) < 0 is b < 0 where a < 0.
    CHECK(choice(Op::Min, 0, pos, across, true) == kChoiceB);
    CHECK(choice(Op::Min, 0, across, pos, true) == kChoiceA);
    CHECK(choice(Op::Max, 0, neg, across, true) == kChoiceB);
    CHECK(choice(Op::Max, 0, across, neg, true) == kChoiceA);
    // A side of one sign that settles the result: min with a negative side, max with a
    // positive one (value rule undecided: [-1, 1] against [-2, -0.5] overlap).
    CHECK(choice(Op::Min, 0, neg, across, true) == kChoiceA);
    CHECK(choice(Op::Max, 0, across, pos, true) == kChoiceB);
    // Straddling both: undecided; an unknown side (NaN may occur): undecided.
    CHECK(choice(Op::Min, 0, across, across, true) == kChoiceBoth);
    CHECK(choice(Op::Min, 0, pos, unknown, true) == kChoiceBoth);
    CHECK(choice(Op::Max, 0, unknown, neg, true) == kChoiceBoth);
    // Immediates: min(a, 0.5) < 0 is a < 0; max(a, -0.5) < 0 is a < 0; max(a, 0.5) never.
    CHECK(choice(Op::MinI, 0.5f, across, across, true) == kChoiceA);
    CHECK(choice(Op::MaxI, -0.5f, across, across, true) == kChoiceA);
    CHECK(choice(Op::MaxI, 0.5f, across, across, true) == kChoiceB);
    CHECK(choice(Op::MinI, -0.5f, across, across, true) == kChoiceB);
    CHECK(choice(Op::MinI, -0.5f, unknown, across, true) == kChoiceBoth);
    // A min whose value another op needs is not sign-only: min(x, y) * 2 ...
    Program p = test::single_op_program(Op::Min, 0);
    Instr twice{Op::MulI};
    twice.out = 3, twice.a = 3, twice.k = 2.0f;
    p.code.push_back(twice);
    Tape t = Tape::from(p);
    t.mark_sign_only();
    CHECK(!(t.code[3].pad & kSignOnly));
    // ... while a chain of min/max up to the output is.
    Tape u = Tape::from(test::single_op_program(Op::Min, 0));
    u.mark_sign_only();
    CHECK((u.code[3].pad & kSignOnly));
}

TEST_CASE("the batch interval evaluator gives a box the same bounds and choices at any lane count") {
    // Lanes run in whole vectors of 16 (runtime/eval/interval_kernel.inl): a box's result must
    // not depend on how many others share the call, or on where the last vector ends.
    auto c = test::compile_text(R"(
        difference() {
            union() { translate([0.5, 0, 0]) sphere(0.3); translate([-0.5, 0.2, 0]) box([0.2, 0.3, 0.2]); }
            translate([0, 0.1, 0]) cylinder(0.15, 2);
        }
    )");
    for (bool sign_only : {false, true}) {
        Tape full = Tape::from(c->cs.distance);
        if (sign_only) full.mark_sign_only();
        IntervalEvaluator all(full.num_regs, full.choices), some(full.num_regs, full.choices);
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f), sz(0.01f, 0.8f);
        float lo[3][kIvLanes], hi[3][kIvLanes];
        for (int l = 0; l < kIvLanes; ++l)
            for (int a = 0; a < 3; ++a) lo[a][l] = u(rng), hi[a][l] = lo[a][l] + sz(rng);
        all.eval(full, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], kIvLanes);
        size_t decided = 0;
        for (int n : {1, 7, 8, 9, 15, 16, 17, 31, 33, 48, 63}) {
            some.eval(full, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], n);
            for (int l = 0; l < n; ++l) {
                INFO("sign_only " << sign_only << ", n " << n << ", lane " << l);
                const Interval x = some.result(l), y = all.result(l);
                CHECK(std::memcmp(&x, &y, sizeof(Interval)) == 0);
                for (uint32_t s = 0; s < full.choices; ++s) {
                    const uint8_t a = all.choices()[size_t(s) * size_t(all.stride()) + size_t(l)];
                    CHECK(some.choices()[size_t(s) * size_t(some.stride()) + size_t(l)] == a);
                    decided += a != kChoiceBoth;
                }
            }
        }
        CHECK(decided > 0);
    }
}

// max(x, -x), the way a simplified tape says |x| where a CSG model's faces coincide, becomes
// abs(x): the same floats but for the sign of a zero, and an interval that is never below 0.
TEST_CASE("fold_abs: max(x, -x) through copies and double negations becomes abs(x)") {
    auto ins = [](Op op, uint16_t out, uint16_t a = 0, uint16_t b = 0, float k = 0.0f) {
        Instr in{op};
        in.out = out, in.a = a, in.b = b, in.k = k;
        return in;
    };
    // a = 10 x - 9; max(-a, -(copy of -a)) is |a|, and so are the other orders below.
    const std::vector<Instr> sheet = {ins(Op::VarX, 0),   ins(Op::MulI, 0, 0, 0, 10), ins(Op::SubI, 0, 0, 0, 9), ins(Op::Neg, 1, 0),
                                      ins(Op::Copy, 2, 1), ins(Op::Neg, 2, 2),          ins(Op::Max, 3, 1, 2)};
    std::vector<uint32_t> scratch;
    std::vector<Instr> code = sheet;
    REQUIRE(fold_abs(code.data(), code.size(), scratch));
    CHECK(code[6].op == Op::Abs);
    CHECK(code[6].a == 1);
    std::vector<Instr> swapped = sheet;
    std::swap(swapped[6].a, swapped[6].b);
    CHECK(fold_abs(swapped.data(), swapped.size(), scratch));
    CHECK(swapped[6].op == Op::Abs);

    // Same floats at points (zeros compare equal whatever their sign), and over a box across
    // the sheet the folded interval starts at 0 where max's starts below it.
    Tape before, after;
    before.assign(sheet.data(), sheet.size(), 3, 4);
    after.assign(code.data(), code.size(), 3, 4);
    BatchVM vm(4);
    float xs[kBatch], ys[kBatch] = {}, zs[kBatch] = {}, want[kBatch];
    for (int i = 0; i < kBatch; ++i) xs[i] = 0.8f + 0.2f * float(i) / float(kBatch - 1);
    xs[0] = 0.9f;
    vm.eval(before.view(), xs, ys, zs, kBatch);
    std::copy_n(vm.output(before.view()), kBatch, want);
    vm.eval(after.view(), xs, ys, zs, kBatch);
    for (int i = 0; i < kBatch; ++i) CHECK(vm.output(after.view())[i] == want[i]);
    IntervalEvaluator iv(4, 1);
    const float lo[3] = {0.8f, 0.0f, 0.0f}, hi[3] = {1.0f, 0.1f, 0.1f};
    iv.eval(before.view(), &lo[0], &hi[0], &lo[1], &hi[1], &lo[2], &hi[2], 1);
    CHECK(iv.result(0).lo < 0.0f);
    iv.eval(after.view(), &lo[0], &hi[0], &lo[1], &hi[1], &lo[2], &hi[2], 1);
    CHECK(iv.result(0).lo == 0.0f);
    CHECK(iv.result(0).hi == Approx(1.0f));

    // Not folded: a register written again between (it no longer holds x), another value,
    // and min(x, -x).
    std::vector<Instr> rewritten = {ins(Op::VarX, 0), ins(Op::Neg, 1, 0), ins(Op::VarY, 0), ins(Op::Max, 2, 0, 1)};
    std::vector<Instr> other = {ins(Op::VarX, 0), ins(Op::VarY, 1), ins(Op::Neg, 1, 1), ins(Op::Max, 2, 0, 1)};
    std::vector<Instr> least = {ins(Op::VarX, 0), ins(Op::Neg, 1, 0), ins(Op::Min, 2, 0, 1)};
    for (auto* c : {&rewritten, &other, &least}) {
        const std::vector<Instr> was = *c;
        CHECK_FALSE(fold_abs(c->data(), c->size(), scratch));
        CHECK(std::memcmp(c->data(), was.data(), was.size() * sizeof(Instr)) == 0);
    }
}
