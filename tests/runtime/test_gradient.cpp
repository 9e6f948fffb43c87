// The forward-mode gradient evaluator (runtime/eval/gradient.cpp): every opcode's derivative,
// from opcodes.def's semantics over dual numbers, against central differences of the VM, and
// the gradients of exact distances (unit length off the surface).
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "runtime/eval/gradient.hpp"
#include "runtime/eval/vm.hpp"
#include "support.hpp"

using namespace sdfc;

namespace {

// Central differences of the VM's first output at p, step h.
glm::vec3 differences(const Program& p, glm::vec3 at, float h) {
    Evaluator ev(p);
    float x[6], y[6], z[6];
    for (int k = 0; k < 6; ++k) {
        glm::vec3 q = at;
        q[k / 2] += (k & 1) ? -h : h;
        x[k] = q.x, y[k] = q.y, z[k] = q.z;
    }
    ev.eval(x, y, z, 6);
    const float* f = ev.output(0);
    return glm::vec3(f[0] - f[1], f[2] - f[3], f[4] - f[5]) / (2.0f * h);
}

Dual gradient(const Program& p, glm::vec3 at) {
    GradientEvaluator g(p.num_regs);
    Dual d;
    g.eval(p.view(), &at.x, &at.y, &at.z, 1, 0.0f, &d);
    return d;
}

}  // namespace

TEST_CASE("gradients: every opcode's derivative agrees with central differences where it is smooth", "[gradient]") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-2.5f, 2.5f), uk(-3.0f, 3.0f);
    int checked = 0;
    for (int o = 0; o < kOpCount; ++o) {
        const Op op = Op(o);
        if (op == Op::VarX || op == Op::VarY || op == Op::VarZ || op == Op::Time || op == Op::Guard) continue;  // (guard: +inf)
        int here = 0;
        for (int trial = 0; trial < 200; ++trial) {
            const float k0 = uk(rng), k = k0 < 0.0f ? std::min(k0, -0.5f) : std::max(k0, 0.5f);  // no period below a step
            const Program p = test::single_op_program(op, k);
            const glm::vec3 at(u(rng), u(rng), u(rng));
            const Dual d = gradient(p, at);
            Evaluator ev(p);
            INFO(op_info(op).mnemonic << " k=" << k << " at (" << at.x << ", " << at.y << ", " << at.z << ")");
            const float v = ev.eval1(at.x, at.y, at.z);
            if (std::isnan(v)) {
                CHECK(std::isnan(d.v));
                continue;
            }
            CHECK(d.v == Approx(v).epsilon(1e-5f).margin(1e-6f));
            // Smooth here: differences at two steps agree (no kink or jump within reach).
            const glm::vec3 f1 = differences(p, at, 1e-2f), f2 = differences(p, at, 5e-3f);
            const glm::vec3 g(d.dx, d.dy, d.dz);
            if (!std::isfinite(f1.x + f1.y + f1.z) || !std::isfinite(g.x + g.y + g.z)) continue;
            if (glm::length(f1 - f2) > 1e-2f * (1.0f + glm::length(f1))) continue;
            CHECK(glm::length(g - f2) <= 2e-2f * (1.0f + glm::length(f2)));
            ++here;
        }
        INFO(op_info(op).mnemonic);
        CHECK(here > 20);  // most points are smooth for every op
        checked += here;
    }
    CHECK(checked > 5000);
}

TEST_CASE("gradients: exact distances have unit gradients, pointing out of the surface", "[gradient]") {
    for (const char* src : {"sphere(1);", "box([2, 1, 1.5]);", "torus(1, 0.3);", "rotate(x = 30, y = 40) box([1, 1, 1]);",
                            "translate([0.5, 0, 0]) scale(2) sphere(0.5);"}) {
        INFO(src);
        auto c = test::compile_text(src);
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(-3.0f, 3.0f);
        for (int i = 0; i < 100; ++i) {
            const glm::vec3 at(u(rng), u(rng), u(rng));
            const Dual d = gradient(c->cs.distance, at);
            if (!(d.v > 0.05f)) continue;  // outside: the gradient of an exact distance has length 1
            CHECK(std::sqrt(d.dx * d.dx + d.dy * d.dy + d.dz * d.dz) == Approx(1.0f).epsilon(1e-3));
            const glm::vec3 f = differences(c->cs.distance, at, 1e-3f);
            CHECK(glm::length(glm::vec3(d.dx, d.dy, d.dz) - f) < 1e-2f);
        }
    }
    // On a box's face the length term is sqrt(0): no derivative of its own, the face's
    // normal from the other term (not NaN).
    auto b = test::compile_text("box([2, 2, 2]);");
    const Dual f = gradient(b->cs.distance, {1.0f, 0.2f, 0.3f});
    CHECK(f.v == Approx(0.0f).margin(1e-6));
    CHECK(f.dx == Approx(1.0f));
    CHECK(f.dy == Approx(0.0f).margin(1e-6));
    CHECK(f.dz == Approx(0.0f).margin(1e-6));
    // A sphere at the origin: the gradient is p / |p|.
    auto s = test::compile_text("sphere(1);");
    const Dual d = gradient(s->cs.distance, {0.0f, 3.0f, 4.0f});
    CHECK(d.v == Approx(4.0f));
    CHECK(d.dx == Approx(0.0f).margin(1e-6));
    CHECK(d.dy == Approx(0.6f));
    CHECK(d.dz == Approx(0.8f));
}
