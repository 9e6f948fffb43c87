// The point suite: every case's value at its points, on every point backend, against the
// case's expectation (opcodes.def semantics, known values and reference formulas, the
// scalar reference for examples). Backends that run the VM's floats must also equal the
// batch VM bit for bit. A backend that is not available here is skipped with a warning.
#include <catch2/catch.hpp>

#include <bit>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "conformance/backends.hpp"
#include "conformance/cases.hpp"

using namespace sdfc;
using namespace sdfc::conformance;

namespace {

template <class B>
void check_points(const std::vector<Case>& cases) {
    B backend;
    if (const std::string why = backend.unavailable(); !why.empty()) {
        WARN("SKIPPED: " << why);
        return;
    }
    BatchVm vm;
    size_t points = 0, failed = 0;
    std::map<std::string, std::map<std::string, int>> known;  // why -> case -> points
    for (const Case& c : cases) {
        const std::vector<float> got = backend.eval(c.program, c.points, c.time);
        if constexpr (requires(B& b) { b.error; }) {
            INFO(c.name << ": " << backend.error);
            REQUIRE(backend.error.empty());
        }
        REQUIRE(got.size() == c.points.size());
        std::vector<float> same;
        if constexpr (B::kVmFloats) same = vm.eval(c.program, c.points, c.time);
        std::ostringstream why;
        why.precision(9);
        int bad = 0;
        for (size_t i = 0; i < c.points.size(); ++i) {
            const Point& p = c.points[i];
            const bool ok = satisfies(got[i], c.expect[i]);
            const bool bits = !B::kVmFloats || std::bit_cast<uint32_t>(got[i]) == std::bit_cast<uint32_t>(same[i]);
            if (ok && bits) continue;
            if constexpr (requires { B::known_difference(c, p, got[i]); }) {
                if (const std::string k = B::known_difference(c, p, got[i]); !k.empty()) {
                    ++known[k][c.name];
                    continue;
                }
            }
            if (bad++ < 8) {
                why << "  at (" << p.x << ", " << p.y << ", " << p.z << "): " << got[i] << ", want " << describe(c.expect[i]);
                if (!bits) why << ", batch VM " << same[i];
                why << "\n";
            }
        }
        points += c.points.size();
        if (bad) {
            ++failed;
            FAIL_CHECK(c.name << ": " << bad << " of " << c.points.size() << " points disagree\n" << why.str());
        }
    }
    std::printf("  %zu cases, %zu points, %zu cases disagreeing\n", cases.size(), points, failed);
    for (const auto& [why, where] : known) {
        std::ostringstream s;
        for (const auto& [name, n] : where) s << " " << name << " (" << n << " points)";
        WARN("known difference: " << why << ":" << s.str());
    }
}

}  // namespace

#define POINT_BACKENDS Scalar, BatchVm, SimplifyOne, SimplifyBatchCompact, SimplifyBatchTrace, SimplifySweep, GlslLlvmpipe, GlslTapeLlvmpipe

TEMPLATE_TEST_CASE("every opcode gives its opcodes.def semantics", "[opcodes]", POINT_BACKENDS) {
    check_points<TestType>(opcode_cases());
}

TEMPLATE_TEST_CASE("every shape and operation gives its known distances and reference formulas", "[shapes]", POINT_BACKENDS) {
    check_points<TestType>(shape_cases());
}

TEMPLATE_TEST_CASE("every example gives the scalar reference's distances", "[examples]", POINT_BACKENDS) {
    REQUIRE_FALSE(example_cases().empty());
    check_points<TestType>(example_cases());
}
