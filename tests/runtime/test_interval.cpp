// Interval arithmetic (runtime/interval.hpp): every opcode's interval encloses what the
// batch VM computes at every point of the box, bit for bit, and a decided choice is the
// VM's choice at every point; simplified tapes compute the same floats as their parent
// inside the box.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "compiler/compile.hpp"
#include "lang/load.hpp"
#include "runtime/interval.hpp"
#include "runtime/vm.hpp"
#include "support.hpp"

using namespace sdfc;

namespace {

// out := op(r0, r1, r2, k) with r0..r2 = x, y, z.
Program one_op(Op op, float k) {
    Program p;
    p.code.push_back(Instr{Op::VarX, 0, 0});
    p.code.push_back(Instr{Op::VarY, 0, 1});
    p.code.push_back(Instr{Op::VarZ, 0, 2});
    Instr in{op};
    in.out = 3, in.a = 0, in.b = 1, in.c = 2, in.k = k;
    p.code.push_back(in);
    p.locs.resize(p.code.size());
    p.num_regs = 4;
    p.outputs = {3};
    p.output_names = {"out"};
    return p;
}

bool inside(float v, Interval r) {
    if (std::isnan(r.lo) || std::isnan(r.hi)) return true;  // unknown: anything
    if (std::isnan(v)) return false;                       // a known interval promises no NaN
    return r.lo <= v && v <= r.hi;
}

}  // namespace

TEST_CASE("every opcode: the interval encloses the VM's value at every point of the box") {
    std::mt19937 rng(12345);
    const float specials[] = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -2.5f, 3.0f, 1e-3f, -1e-3f, 7.25f, -100.0f, 1e30f, -1e30f,
                              1.5707964f, 3.1415927f, -3.1415927f, 6.2831855f, 1e-38f};
    std::uniform_real_distribution<float> u(-4.0f, 4.0f);
    std::uniform_int_distribution<int> pick(0, int(std::size(specials)) - 1);
    auto endpoint = [&]() { return (rng() % 3 == 0) ? specials[pick(rng)] : u(rng) * ((rng() % 4 == 0) ? 10.0f : 1.0f); };
    auto box = [&]() {
        float a = endpoint(), b = (rng() % 5 == 0) ? a : endpoint();
        return Interval{std::min(a, b), std::max(a, b)};
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
            Program p = one_op(op, k);
            Evaluator ev(p);
            float xs[kBatch], ys[kBatch], zs[kBatch];
            auto sample = [&](Interval I, int i) {
                if (i == 0) return I.lo;
                if (i == 1) return I.hi;
                float t = float(rng() % 1000) / 999.0f;
                return std::clamp(I.lo + (I.hi - I.lo) * t, I.lo, I.hi);
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
            ev.eval_code(t.code.data(), t.code.size(), xs, ys, zs, kBatch);
            for (int i = 0; i < kBatch; ++i) {
                REQUIRE(std::bit_cast<uint32_t>(ev.reg_data(t.out)[i]) == std::bit_cast<uint32_t>(want[i]));
                REQUIRE(inside(want[i], r));
            }
        }
    }
    REQUIRE(shorter > 0);
}
