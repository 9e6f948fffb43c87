// The box suite: over random boxes, every case's interval (on every box backend) encloses
// what the batch VM computes at every point of the box, bit for bit, and a decided choice is
// the VM's choice at every point; a tape simplified for a box (every simplifier) computes the
// full program's floats there. Opcode rows get boxes with special, infinite and unknown
// ([NaN, NaN]: any value) ends and a fresh immediate per box.
#include <catch2/catch.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <sstream>
#include <type_traits>

#include "conformance/backends.hpp"
#include "conformance/cases.hpp"
#include "support.hpp"

using namespace sdfc;
using namespace sdfc::conformance;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

bool unknown(Interval r) { return std::isnan(r.lo) || std::isnan(r.hi); }

bool inside(float v, Interval r) {
    if (unknown(r)) return true;      // unknown: anything
    if (std::isnan(v)) return false;  // a known interval promises no NaN
    return r.lo <= v && v <= r.hi;
}

uint32_t seed() { return std::getenv("SDFC_TEST_SEED") ? uint32_t(std::atoi(std::getenv("SDFC_TEST_SEED"))) : 12345u; }

// Boxes and points for the opcode rows (the generator of the old every-opcode interval test).
struct OpcodeBoxes {
    std::mt19937 rng{seed()};
    static constexpr float specials[] = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -2.5f, 3.0f, 1e-3f, -1e-3f, 7.25f, -100.0f, 1e30f, -1e30f,
                                         1.5707964f, 3.1415927f, -3.1415927f, 6.2831855f, 1e-38f};
    std::uniform_real_distribution<float> u{-4.0f, 4.0f};
    std::uniform_int_distribution<int> pick{0, int(std::size(specials)) - 1};
    float endpoint() { return (rng() % 3 == 0) ? specials[pick(rng)] : u(rng) * ((rng() % 4 == 0) ? 10.0f : 1.0f); }
    float immediate(int trial) { return (trial % 7 == 0) ? specials[pick(rng)] : u(rng); }
    // Mostly finite, some with infinite ends, some unknown.
    Interval interval() {
        const int kind = int(rng() % 16);
        if (kind == 0) return Interval{kNaN, kNaN};
        float a = endpoint(), b = (rng() % 5 == 0) ? a : endpoint();
        Interval r{std::min(a, b), std::max(a, b)};
        if (kind == 1) r.lo = -kInf;
        if (kind == 2) r.hi = kInf;
        if (kind == 3) r = Interval{-kInf, kInf};
        return r;
    }
    Box box(Op op, int trial) {
        Box b{interval(), interval(), interval()};
        if (op == Op::Select && trial % 3 == 0) b.x = Interval{0.0f, 0.0f};
        return b;
    }
    // Ends, and points between them; anything for an unknown interval.
    float sample(Interval I, int i) {
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
    }
    std::vector<Point> points(const Box& b) {
        std::vector<Point> p;
        for (int i = 0; i < 64; ++i) p.push_back({sample(b.x, i % 3 == 2 ? 2 : i % 2), sample(b.y, (i / 2) % 3), sample(b.z, (i / 6) % 3)});
        return p;
    }
};

// Boxes inside [-range, range]^3 for shapes and examples, corners and random points in each.
struct SceneBoxes {
    std::mt19937 rng{seed() + 1};
    std::vector<Box> boxes(float range, int n) {
        std::uniform_real_distribution<float> u(-range, range), sz(0.0f, 0.5f * range);
        std::vector<Box> out;
        for (int i = 0; i < n; ++i) {
            auto side = [&] {
                const float lo = u(rng), s = (i % 8 == 0) ? 0.0f : sz(rng) * sz(rng) / range;
                return Interval{lo, lo + s};
            };
            out.push_back({side(), side(), side()});
        }
        return out;
    }
    std::vector<Point> points(const Box& b) {
        std::vector<Point> p;
        auto in = [&](Interval I, int i, int bit) {
            if (i < 8) return (i >> bit) & 1 ? I.hi : I.lo;
            return std::clamp(I.lo + (I.hi - I.lo) * float(rng() % 1001) / 1000.0f, I.lo, I.hi);
        };
        for (int i = 0; i < 16; ++i) p.push_back({in(b.x, i, 0), in(b.y, i, 1), in(b.z, i, 2)});
        return p;
    }
};

std::string show(const Box& b) {
    std::ostringstream s;
    s.precision(9);
    s << "[" << b.x.lo << "," << b.x.hi << "] x [" << b.y.lo << "," << b.y.hi << "] x [" << b.z.lo << "," << b.z.hi << "]";
    return s.str();
}

// The interval over `box` encloses the VM at `pts`; for a single-op program, a decided choice
// also gives the chosen operand's bits.
void check_box(const Case& c, const Program& prog, float k, const Box& box, const BoxResult& r, const std::vector<Point>& pts) {
    INFO(c.name << " k=" << k << " box " << show(box) << " -> [" << r.value.lo << "," << r.value.hi << "]");
    // Unknown is both ends NaN, never one.
    REQUIRE(std::isnan(r.value.lo) == std::isnan(r.value.hi));
    const std::vector<float> vm = BatchVm{}.eval(prog, pts, c.time);
    for (size_t i = 0; i < pts.size(); ++i) {
        INFO("point (" << pts[i].x << ", " << pts[i].y << ", " << pts[i].z << ") = " << vm[i]);
        REQUIRE(inside(vm[i], r.value));
        if (c.kind != Case::Opcode || r.choices.empty()) continue;
        const float chosen[] = {0.0f, pts[i].x, op_info(c.op).has_imm ? k : pts[i].y, pts[i].z};
        if (r.choices[0] != kChoiceBoth) REQUIRE(std::bit_cast<uint32_t>(vm[i]) == std::bit_cast<uint32_t>(chosen[r.choices[0]]));
    }
}

}  // namespace

TEMPLATE_TEST_CASE("every opcode: the interval encloses the VM at every point of the box, and a decided choice is the VM's",
                   "[opcodes][interval]", ScalarInterval, BatchInterval) {
    OpcodeBoxes gen;
    const Case* last = nullptr;
    for (const Case& c : opcode_cases()) {
        if (is_input(c.op) || (last && last->op == c.op)) continue;  // inputs are the box; one row each
        last = &c;
        for (int trial = 0; trial < 300; ++trial) {
            const float k = gen.immediate(trial);
            const Program p = test::single_op_program(c.op, k);
            const Box box = gen.box(c.op, trial);
            const BoxResult r = TestType{}.eval(p, {box}, c.time).at(0);
            REQUIRE(r.choices.size() == (is_choice_op(c.op) ? 1u : 0u));
            check_box(c, p, k, box, r, gen.points(box));
        }
    }
}

TEMPLATE_TEST_CASE("every shape, operation and example: the interval encloses the VM in every box", "[shapes][examples][interval]",
                   ScalarInterval, BatchInterval) {
    SceneBoxes gen;
    for (const auto* cases : {&shape_cases(), &example_cases()})
        for (const Case& c : *cases) {
            const std::vector<Box> boxes = gen.boxes(c.range, 64);
            const std::vector<BoxResult> r = TestType{}.eval(c.program, boxes, c.time);
            REQUIRE(r.size() == boxes.size());
            for (size_t i = 0; i < boxes.size(); ++i) check_box(c, c.program, 0.0f, boxes[i], r[i], gen.points(boxes[i]));
        }
}

TEMPLATE_TEST_CASE("every case: a tape simplified for a box computes the full program's floats in it", "[simplify]",
                   SimplifyOne, SimplifyBatchCompact, SimplifyBatchTrace, SimplifySignOnly, SimplifyMinChain, SimplifySweep) {
    auto check = [](const Case& c, const Program& p, const std::vector<Box>& boxes, const std::vector<std::vector<Point>>& pts) {
        const auto got = TestType{}.eval_in_boxes(p, boxes, pts, c.time);
        for (size_t b = 0; b < boxes.size(); ++b) {
            const std::vector<float> want = BatchVm{}.eval(p, pts[b], c.time);
            for (size_t i = 0; i < pts[b].size(); ++i) {
                INFO(c.name << " box " << show(boxes[b]) << " point (" << pts[b][i].x << ", " << pts[b][i].y << ", " << pts[b][i].z
                            << "): simplified " << got[b][i] << ", full " << want[i]);
                if constexpr (std::is_same_v<TestType, SimplifySignOnly>)
                    REQUIRE((got[b][i] < 0.0f) == (want[i] < 0.0f));  // (NaN is not < 0)
                else
                    REQUIRE((std::bit_cast<uint32_t>(got[b][i]) == std::bit_cast<uint32_t>(want[i]) ||
                             (std::isnan(got[b][i]) && std::isnan(want[i]))));
            }
        }
    };
    OpcodeBoxes ops;
    for (const Case& c : opcode_cases()) {
        std::vector<Box> boxes;
        std::vector<std::vector<Point>> pts;
        for (int trial = 0; trial < 64; ++trial) {
            boxes.push_back(ops.box(c.op, trial));
            pts.push_back(ops.points(boxes.back()));
        }
        check(c, c.program, boxes, pts);
    }
    SceneBoxes gen;
    for (const auto* cases : {&shape_cases(), &example_cases()})
        for (const Case& c : *cases) {
            const std::vector<Box> boxes = gen.boxes(c.range, 64);
            std::vector<std::vector<Point>> pts;
            for (const Box& b : boxes) pts.push_back(gen.points(b));
            check(c, c.program, boxes, pts);
        }
}
