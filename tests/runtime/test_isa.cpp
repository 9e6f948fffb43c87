// The batch kernels' copies for each instruction set (runtime/eval/isa.hpp) compute the same
// floats: the VM's distances, the interval evaluator's bounds and choices, and so the same
// pictures, bit for bit, as the baseline x86-64 copy. (The build compiles without FP
// contraction, so no copy fuses a multiply and an add the others round twice.)
#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "lang/load.hpp"
#include "runtime/cpu/tracer.hpp"
#include "runtime/eval/interval.hpp"
#include "runtime/eval/isa.hpp"
#include "runtime/eval/vm.hpp"
#include "support.hpp"

using namespace sdfc;

namespace {

struct Restore {
    Isa was = current_isa();
    ~Restore() { set_isa(was); }
};

std::vector<Isa> isas() {
    std::vector<Isa> out;
    for (int i = 0; i <= static_cast<int>(best_isa()); ++i) out.push_back(static_cast<Isa>(i));
    return out;
}

std::vector<std::string> examples() {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(std::string(SDFC_SOURCE_DIR) + "/examples"))
        if (e.path().extension() == ".sdf") out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

// Every bit of the VM's distances, the intervals' bounds and choices, and the sweep's values
// (SweepVM: each box's 64 points through its simplified tape) at fixed points and boxes.
std::vector<uint32_t> fingerprint(const Program& p) {
    std::vector<uint32_t> bits;
    auto put = [&](float v) {
        uint32_t u;
        std::memcpy(&u, &v, 4);
        bits.push_back(u);
    };
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-4.0f, 4.0f), sz(0.001f, 2.0f);
    BatchVM vm(p.num_regs);
    const Tape tape = Tape::from(p);
    IntervalEvaluator iv(tape.num_regs, tape.choices);
    BatchScratch masks;
    SweepVM sweep;
    for (int round = 0; round < 8; ++round) {
        const int n = round == 7 ? kBatch : 8 * round + 5;  // every kernel (one per lane count: 8, 16, ... 64)
        float x[kBatch], y[kBatch], z[kBatch], xh[kBatch], yh[kBatch], zh[kBatch];
        for (int i = 0; i < kBatch; ++i) {
            x[i] = u(rng), y[i] = u(rng), z[i] = u(rng);
            xh[i] = x[i] + sz(rng), yh[i] = y[i] + sz(rng), zh[i] = z[i] + sz(rng);
        }
        vm.eval(p.view(), x, y, z, n, 0.5f);
        for (int i = 0; i < n; ++i) put(vm.output(p.view())[i]);
        iv.eval(tape, x, xh, y, yh, z, zh, n, 0.5f);
        for (int i = 0; i < n; ++i) put(iv.result(i).lo), put(iv.result(i).hi);
        for (uint32_t s = 0; s < tape.choices; ++s)
            for (int i = 0; i < n; ++i) bits.push_back(iv.choices()[s * iv.stride() + i]);
        const uint64_t lanes = n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1;
        simplify_masks(tape, iv.choices(), iv.stride(), lanes, masks);
        if (!tape.linked || tape.out_def == Tape::kNone) continue;
        std::vector<float> in(size_t(n) * 3 * kBatch);
        const float* px[kIvLanes];
        const float* py[kIvLanes];
        const float* pz[kIvLanes];
        for (int l = 0; l < n; ++l) {
            float* q = in.data() + size_t(l) * 3 * kBatch;
            for (int i = 0; i < kBatch; ++i) {
                const float f = float(i) / float(kBatch - 1);
                q[i] = x[l] + (xh[l] - x[l]) * f;
                q[kBatch + i] = y[l] + (yh[l] - y[l]) * (1.0f - f);
                q[2 * kBatch + i] = z[l] + (zh[l] - z[l]) * f * f;
            }
            px[l] = q, py[l] = q + kBatch, pz[l] = q + 2 * kBatch;
        }
        sweep.eval(tape, iv.choices(), iv.stride(), masks.mask.data(), lanes, px, py, pz, 0.5f);
        for (int l = 0; l < n; ++l)
            for (int i = 0; i < kBatch; ++i) put(sweep.output(l)[i]);
    }
    return bits;
}

std::string first_difference(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    if (a.size() != b.size()) return "sizes " + std::to_string(a.size()) + " and " + std::to_string(b.size());
    for (size_t i = 0; i < a.size(); ++i)
        if (a[i] != b[i]) {
            float x, y;
            std::memcpy(&x, &a[i], 4);
            std::memcpy(&y, &b[i], 4);
            return "word " + std::to_string(i) + ": " + std::to_string(x) + " against the baseline's " + std::to_string(y);
        }
    return "";
}

}  // namespace

TEST_CASE("isa: set_isa keeps to what the CPU and the build have") {
    Restore r;
    CHECK(set_isa(Isa::Baseline) == Isa::Baseline);
    CHECK(current_isa() == Isa::Baseline);
    CHECK(set_isa(Isa::Avx512) == best_isa());
    CHECK(current_isa() == best_isa());
    if (!isa_dispatch()) CHECK(best_isa() == Isa::Baseline);
    CHECK(std::string(isa_name(Isa::Baseline)) == (isa_dispatch() ? "x86-64" : std::string(isa_name(Isa::Baseline))));
}

TEST_CASE("isa: every example's distances and intervals are the same bits with every kernel") {
    Restore r;
    if (isas().size() == 1) WARN("one kernel in this build or on this CPU: nothing to compare");
    for (const std::string& path : examples()) {
        INFO(path);
        SourceManager sm;
        const CompiledScene cs = compile_scene(load_scene(sm, path));
        set_isa(Isa::Baseline);
        const std::vector<uint32_t> base = fingerprint(cs.distance);
        const std::vector<uint32_t> base_mat = fingerprint(cs.shading);
        for (Isa isa : isas()) {
            INFO(isa_name(isa));
            REQUIRE(set_isa(isa) == isa);
            CHECK(first_difference(fingerprint(cs.distance), base) == "");
            CHECK(first_difference(fingerprint(cs.shading), base_mat) == "");
        }
    }
}

TEST_CASE("isa: the same picture with every kernel") {
    Restore r;
    for (const char* name : {"showcase", "recursive1", "gyroid-ball"}) {
        INFO(name);
        SourceManager sm;
        CompiledScene cs = compile_scene(load_scene(sm, std::string(SDFC_SOURCE_DIR) + "/examples/" + name + ".sdf"));
        cs.render.width = 160;
        cs.render.height = 90;
        cs.render.samples = 1;
        set_isa(Isa::Baseline);
        const Image base = render(cs, RenderOptions{});
        for (Isa isa : isas()) {
            INFO(isa_name(isa));
            set_isa(isa);
            CHECK(render(cs, RenderOptions{}).pixels == base.pixels);
        }
    }
}

// The transcendentals run a vector at a time (runtime/eval/vmath.inl) through SLEEF's functions
// of the scalar reference's family: every kernel gives the scalar semantics' bits (NaN for NaN),
// at special values, at huge arguments (sin's slow reduction), and at random ones.
TEST_CASE("isa: the transcendental ops give the scalar semantics' bits with every kernel") {
    Restore r;
    std::vector<float> xs = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -0.5f, 2.0f, -8.0f, 3.0f, 1e-40f, -1e-40f, 1e-8f, 88.7f, 89.0f,
                             -87.3f, -104.0f, 1e5f, -1e5f, 1e30f, 3.4e38f, INFINITY, -INFINITY, NAN, 0.9999999f, 1.0000001f};
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> small(-10.0f, 10.0f);
    std::uniform_int_distribution<uint32_t> bits;
    while (xs.size() < 4 * kBatch) {
        xs.push_back(small(rng));
        const uint32_t u = bits(rng);
        float f;
        std::memcpy(&f, &u, 4);
        xs.push_back(f);
    }
    std::vector<float> ys(xs.rbegin(), xs.rend());  // second operands: every pairing of kinds
    const float zs[kBatch] = {};
    auto same = [](float a, float b) { return std::memcmp(&a, &b, 4) == 0 || (std::isnan(a) && std::isnan(b)); };
    for (Op op : {Op::Exp, Op::Log, Op::Sin, Op::Cos, Op::Tan, Op::Asin, Op::Acos, Op::Atan, Op::Atan2, Op::Pow, Op::PowI}) {
        for (float k : {3.0f, 0.5f, -2.0f}) {
            if (op != Op::PowI && k != 3.0f) continue;
            INFO(op_info(op).mnemonic << " k=" << k);
            const Program p = test::single_op_program(op, k);
            BatchVM vm(p.num_regs);
            for (Isa isa : isas()) {
                INFO(isa_name(isa));
                REQUIRE(set_isa(isa) == isa);
                int wrong = 0;
                std::string first;
                for (size_t i0 = 0; i0 < xs.size(); i0 += kBatch) {
                    // Partial batches too: 64, 55, ... 1 points run every kernel (one per lane
                    // count: 8, 16, ... 64), within the values left.
                    const int full = static_cast<int>(std::min<size_t>(kBatch, xs.size() - i0));
                    for (int n = full - 5 * int(i0 == 0); n > 0; n -= 9) {
                        vm.eval(p.view(), xs.data() + i0, ys.data() + i0, zs, n, 0.0f);
                        for (int i = 0; i < n; ++i) {
                            const float want = eval_op(op, xs[i0 + i], ys[i0 + i], 0.0f, k), got = vm.output(p.view())[i];
                            if (!same(got, want) && wrong++ == 0)
                                first = std::to_string(xs[i0 + i]) + ", " + std::to_string(ys[i0 + i]) + ": " +
                                        std::to_string(got) + " for " + std::to_string(want);
                        }
                    }
                }
                CHECK(first == "");
                CHECK(wrong == 0);
            }
        }
    }
    // Special values as C's: what scripts may rely on.
    CHECK(eval_op(Op::Pow, -8.0f, 3.0f, 0.0f, 0.0f) == -512.0f);
    CHECK(std::isnan(eval_op(Op::Pow, -8.0f, 1.0f / 3.0f, 0.0f, 0.0f)));
    CHECK(eval_op(Op::Pow, 0.0f, -1.0f, 0.0f, 0.0f) == INFINITY);
    CHECK(eval_op(Op::Pow, 1.0f, NAN, 0.0f, 0.0f) == 1.0f);
    CHECK(eval_op(Op::Pow, 2.0f, 0.5f, 0.0f, 0.0f) == std::sqrt(2.0f));
    CHECK(eval_op(Op::PowI, NAN, 0.0f, 0.0f, 0.0f) == 1.0f);
    CHECK(eval_op(Op::Exp, 0.0f, 0.0f, 0.0f, 0.0f) == 1.0f);
    CHECK(eval_op(Op::Exp, -INFINITY, 0.0f, 0.0f, 0.0f) == 0.0f);
    CHECK(eval_op(Op::Exp, 89.0f, 0.0f, 0.0f, 0.0f) == INFINITY);
    CHECK(eval_op(Op::Log, 1.0f, 0.0f, 0.0f, 0.0f) == 0.0f);
    CHECK(eval_op(Op::Log, 0.0f, 0.0f, 0.0f, 0.0f) == -INFINITY);
    CHECK(std::isnan(eval_op(Op::Log, -1.0f, 0.0f, 0.0f, 0.0f)));
    CHECK(eval_op(Op::Sin, 0.0f, 0.0f, 0.0f, 0.0f) == 0.0f);
    CHECK(eval_op(Op::Cos, 0.0f, 0.0f, 0.0f, 0.0f) == 1.0f);
    CHECK(eval_op(Op::Atan2, 0.0f, -1.0f, 0.0f, 0.0f) == Approx(3.14159265f));
    CHECK(eval_op(Op::Asin, 2.0f, 0.0f, 0.0f, 0.0f) == Approx(1.57079633f));  // clamped, as GLSL's asin(clamp(...))
    CHECK(std::fabs(eval_op(Op::Sin, 1e5f, 0.0f, 0.0f, 0.0f) - std::sin(1e5f)) <= 1e-6f);
}
