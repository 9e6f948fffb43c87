// Interval arithmetic (runtime/eval/interval.hpp): every opcode's interval encloses what the
// batch VM computes at every point of the box, bit for bit, and a decided choice is the
// VM's choice at every point; simplified tapes compute the same floats as their parent
// inside the box.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>

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

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

}  // namespace

TEST_CASE("every opcode: the interval encloses the VM's value at every point of the box") {
    std::mt19937 rng(std::getenv("SDFC_TEST_SEED") ? uint32_t(std::atoi(std::getenv("SDFC_TEST_SEED"))) : 12345u);
    const float specials[] = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -2.5f, 3.0f, 1e-3f, -1e-3f, 7.25f, -100.0f, 1e30f, -1e30f,
                              1.5707964f, 3.1415927f, -3.1415927f, 6.2831855f, 1e-38f};
    std::uniform_real_distribution<float> u(-4.0f, 4.0f);
    std::uniform_int_distribution<int> pick(0, int(std::size(specials)) - 1);
    auto endpoint = [&]() { return (rng() % 3 == 0) ? specials[pick(rng)] : u(rng) * ((rng() % 4 == 0) ? 10.0f : 1.0f); };
    // Boxes: mostly finite, some with infinite ends, some unknown ([NaN, NaN]: any value).
    auto box = [&]() {
        const int kind = int(rng() % 16);
        if (kind == 0) return Interval{kNaN, kNaN};
        float a = endpoint(), b = (rng() % 5 == 0) ? a : endpoint();
        Interval r{std::min(a, b), std::max(a, b)};
        if (kind == 1) r.lo = -kInf;
        if (kind == 2) r.hi = kInf;
        if (kind == 3) r = Interval{-kInf, kInf};
        return r;
    };
    for (int o = 0; o < kOpCount; ++o) {
        const Op op = static_cast<Op>(o);
        if (is_input(op)) continue;
        for (int trial = 0; trial < 300; ++trial) {
            const float k = (trial % 7 == 0) ? specials[pick(rng)] : u(rng);
            Interval A = box(), B = box(), C = box();
            if (op == Op::Select && trial % 3 == 0) A = Interval{0.0f, 0.0f};
            uint8_t choice = 0;
            const Interval r = eval_interval(op, A, B, C, k, &choice);
            // Unknown is both ends NaN, never one.
            INFO(op_info(op).mnemonic << " k=" << k << " a=[" << A.lo << "," << A.hi << "] b=[" << B.lo << "," << B.hi << "] c=[" << C.lo << "," << C.hi << "] -> [" << r.lo << "," << r.hi << "]");
            REQUIRE(std::isnan(r.lo) == std::isnan(r.hi));
            Program p = test::single_op_program(op, k);
            Evaluator ev(p);
            float xs[kBatch], ys[kBatch], zs[kBatch];
            auto sample = [&](Interval I, int i) {
                if (unknown(I)) {
                    const float any[] = {kNaN, kInf, -kInf, 0.0f, 1e30f, -2.5f, 0.75f};
                    return any[rng() % std::size(any)];
                }
                if (i == 0) return I.lo;
                if (i == 1) return I.hi;
                float lo = std::isinf(I.lo) ? std::max(-1e6f, std::min(I.hi, 0.0f) - 10.0f) : I.lo;
                float hi = std::isinf(I.hi) ? std::min(1e6f, std::max(I.lo, 0.0f) + 10.0f) : I.hi;
                float t = float(rng() % 1000) / 999.0f;
                return std::clamp(lo + (hi - lo) * t, I.lo, I.hi);
            };
            for (int i = 0; i < kBatch; ++i) {
                xs[i] = sample(A, i % 3 == 2 ? 2 : i % 2);
                ys[i] = sample(B, (i / 2) % 3);
                zs[i] = sample(C, (i / 6) % 3);
            }
            ev.eval(xs, ys, zs, kBatch, 0.0f);
            for (int i = 0; i < kBatch; ++i) {
                const float v = ev.output(0)[i];
                INFO(op_info(op).mnemonic << " k=" << k << " a=[" << A.lo << "," << A.hi << "] b=[" << B.lo << "," << B.hi
                                         << "] c=[" << C.lo << "," << C.hi << "] -> [" << r.lo << "," << r.hi
                                         << "] point (" << xs[i] << "," << ys[i] << "," << zs[i] << ") = " << v);
                REQUIRE(inside(v, r));
                if (choice == kChoiceA) REQUIRE(std::bit_cast<uint32_t>(v) == std::bit_cast<uint32_t>(xs[i]));
                if (choice == kChoiceB) {
                    const float w = op_info(op).has_imm ? k : ys[i];
                    REQUIRE(std::bit_cast<uint32_t>(v) == std::bit_cast<uint32_t>(w));
                }
                if (choice == kChoiceC) REQUIRE(std::bit_cast<uint32_t>(v) == std::bit_cast<uint32_t>(zs[i]));
            }
        }
    }
}

TEST_CASE("is_choice_op: exactly the ops whose interval can pick a side") {
    for (int o = 0; o < kOpCount; ++o) {
        const Op op = static_cast<Op>(o);
        const bool want = op == Op::Min || op == Op::Max || op == Op::MinI || op == Op::MaxI || op == Op::Select;
        REQUIRE(is_choice_op(op) == want);
    }
}

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
