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

// Every bit of the VM's distances and the intervals' bounds and choices at fixed points and boxes.
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
    for (int round = 0; round < 8; ++round) {
        const int n = round == 7 ? 13 : kBatch;  // and a partial batch
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
