// Properties of operations that relate two evaluations (periodicity, invariance under
// turns, a bounded perturbation). Known distances and reference formulas of every shape
// and operation run on every backend in tests/conformance/cases_operations.cpp.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "support.hpp"

using namespace sdfc;

namespace {

bool close(double got, double want, double tol = 1e-5) { return std::fabs(got - want) <= tol * (1 + std::fabs(want)); }

struct Field {
    std::unique_ptr<test::Compiled> c;
    explicit Field(const std::string& src) : c(test::compile_text(src)) {}
    float operator()(float x, float y, float z) const { return test::dist(c->cs, x, y, z); }
};

template <class F>
void for_random_points(int n, float range, F&& f) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> u(-range, range);
    for (int i = 0; i < n; ++i) f(u(rng), u(rng), u(rng));
}

}  // namespace

TEST_CASE("repeat: infinite is periodic") {
    Field r("repeat([3, 0, 3]) sphere(0.5);");
    for_random_points(100, 4, [&](float x, float y, float z) {
        CHECK(close(r(x, y, z), r(x + 3, y, z), 1e-4));
        CHECK(close(r(x, y, z), r(x, y, z - 6), 1e-4));
    });
}

TEST_CASE("polar_repeat is invariant under turns of 360/n about y") {
    Field p("polar_repeat(6) translate([2, 0, 0]) sphere(0.3);");
    for_random_points(100, 3, [&](float x, float y, float z) {
        float a = 3.14159265f / 3;
        float rx = std::cos(a) * x - std::sin(a) * z, rz = std::sin(a) * x + std::cos(a) * z;
        CHECK(close(p(x, y, z), p(rx, y, rz), 1e-4));
    });
}

TEST_CASE("displace perturbs the shape boundedly and deterministically") {
    Field d("displace(0.1, 4) sphere(1);");
    Field s("sphere(1);");
    bool differs = false;
    for_random_points(200, 2, [&](float x, float y, float z) {
        // The displaced distance is scaled by its Lipschitz bound, so compare unscaled.
        float lip = 1.0f + 0.1f * 4 * om::kNoiseLipschitz;
        float raw = d(x, y, z) * lip;
        CHECK(std::fabs(raw - s(x, y, z)) <= 0.1f * 1.2f);
        differs |= std::fabs(raw - s(x, y, z)) > 1e-3f;
    });
    CHECK(differs);
    CHECK(d(0.3f, 0.4f, 0.5f) == d(0.3f, 0.4f, 0.5f));  // deterministic
}
