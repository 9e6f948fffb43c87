// Every operation of LANGUAGE.md section 6: a known distance or a defining property.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "support.hpp"

using namespace sdfc;
using test::dist_of;

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

TEST_CASE("union, intersection, difference, xor") {
    const char* a = "sphere(1);";
    (void)a;
    Field u("union { sphere(1); translate([1.5, 0, 0]) sphere(1); }");
    Field i("intersection { sphere(1); translate([1.5, 0, 0]) sphere(1); }");
    Field d("difference { sphere(1); translate([1.5, 0, 0]) sphere(1); }");
    Field x("xor { sphere(1); translate([1.5, 0, 0]) sphere(1); }");
    for_random_points(200, 3, [&](float px, float py, float pz) {
        float s1 = std::sqrt(px * px + py * py + pz * pz) - 1;
        float s2 = std::sqrt((px - 1.5f) * (px - 1.5f) + py * py + pz * pz) - 1;
        CHECK(close(u(px, py, pz), std::min(s1, s2)));
        CHECK(close(i(px, py, pz), std::max(s1, s2)));
        CHECK(close(d(px, py, pz), std::max(s1, -s2)));
        CHECK(close(x(px, py, pz), std::max(std::min(s1, s2), -std::max(s1, s2))));
    });
    // Difference takes the first minus all the rest.
    Field d3("difference { box(4); sphere(1); translate([0, 0, 2]) sphere(1); }");
    CHECK(d3(0, 0, 0) > 0);
    CHECK(d3(0, 0, 2) > 0);
    CHECK(d3(1.5, 1.5, 0) < 0);
}

TEST_CASE("a for statement in a CSG block is one operand, the union of its iterations") {
    // LANGUAGE.md section 4: "union of the iterations"; as in OpenSCAD.
    Field d("difference {\n for (x = [-1, 1]) translate([x, 0, 0]) sphere(0.5);\n sphere(0.2);\n}");
    CHECK(close(d(1, 0, 0), -0.5));
    CHECK(close(d(-1, 0, 0), -0.5));
    CHECK(close(d(0, 0, 0), 0.5));
    Field i("intersection { for (x = [-1, 1]) translate([x * 0.5, 0, 0]) sphere(1); box(10); }");
    CHECK(close(i(1.4f, 0, 0), -0.1f));
    // Cut by a loop: the rest of a difference may be a loop too.
    Field d2("difference { box(4); for (z = [-1, 1]) translate([0, 0, z]) sphere(0.5); }");
    CHECK(close(d2(0, 0, 1), 0.5));
    CHECK(d2(0, 0, 0) < 0);
    // A lone loop is the first operand and nothing is subtracted.
    Field d3("difference { for (x = [-1, 1]) translate([x, 0, 0]) sphere(0.5); }");
    CHECK(close(d3(1, 0, 0), -0.5));
    CHECK(close(d3(-1, 0, 0), -0.5));
    // Union-like blocks take the iterations as operands: a smooth union blends them.
    Field su("smooth_union(1) { for (x = [-1, 1]) translate([x, 0, 0]) sphere(0.8); sphere(0.1); }");
    Field hu("union { for (x = [-1, 1]) translate([x, 0, 0]) sphere(0.8); sphere(0.1); }");
    CHECK(close(hu(0, 1, 0), std::sqrt(2.0f) - 0.8f));
    CHECK(su(0, 1, 0) < hu(0, 1, 0) - 0.1f);
}

TEST_CASE("smooth operations equal the hard ones beyond k and blend within") {
    Field su("smooth_union(0.5) { sphere(1); translate([3, 0, 0]) sphere(1); }");
    Field si("smooth_intersection(0.5) { sphere(1); translate([1, 0, 0]) sphere(1); }");
    Field sd("smooth_difference(0.5) { sphere(1); translate([1, 0, 0]) sphere(1); }");
    // Far from the blend region the result is exact.
    CHECK(close(su(-2, 0, 0), 1));
    CHECK(close(si(-1, 0, 0), 1));  // a = 0, b = 1: beyond k
    // Where both distances are equal the quadratic smin lowers the union by k/4.
    CHECK(close(su(1.5, 0, 0), 0.5 - 0.125));
    CHECK(close(si(0.5, 0, 0), -0.5 + 0.125));
    // Difference: b's inside carved out; at a == -b the blend raises by k/4.
    CHECK(close(sd(0, 0, 0), 0));
    CHECK(close(sd(-0.5, 0, 0), -0.5 + 0.125));
    for_random_points(300, 3, [&](float px, float py, float pz) {
        float a = std::sqrt(px * px + py * py + pz * pz) - 1;
        float b = std::sqrt((px - 3) * (px - 3) + py * py + pz * pz) - 1;
        if (std::fabs(a - b) > 0.5f) CHECK(close(su(px, py, pz), std::min(a, b)));
        else CHECK(su(px, py, pz) <= std::min(a, b) + 1e-6f);
    });
}

TEST_CASE("chamfer and stairs operations follow hg_sdf (chamfer's diagonal halved: same surface, 1-Lipschitz)") {
    Field cu("chamfer_union(0.4) { translate([-5, 0, 0]) box([10, 10, 10]); translate([0, -5, 0]) box([10, 10, 10]); }");
    // Two boxes meeting at a right angle (x < 0 and y < 0 solids): the chamfer cuts the corner.
    CHECK(close(cu(0.3, 0.3, 0), std::min(0.3, (0.3 + 0.3 - 0.4) * 0.5)));
    CHECK(close(cu(3, 3, 0), (3 + 3 - 0.4) * 0.5));  // a bound there: below the true 3
    Field ci("chamfer_intersection(0.4) { box(2); translate([0.5, 0, 0]) box(2); }");
    CHECK(close(ci(0, 0, 0), std::max({-1.0, -0.5, (-1 - 0.5 + 0.4) * 0.5})));
    Field cd("chamfer_difference(0.4) { box(2); translate([2, 0, 0]) box(2); }");
    CHECK(cd(0.95f, 0.95f, 0) > -0.05f);
    auto stairs = [](double a, double b, double r, double n) {
        double s = r / n, u = b - r;
        double m = (u - a + s) - 2 * s * std::floor((u - a + s) / (2 * s));
        return std::min(std::min(a, b), 0.5 * (u + a + std::fabs(m - s)));
    };
    Field st("stairs_union(0.5, 3) { translate([-5, 0, 0]) box([10, 10, 10]); translate([0, -5, 0]) box([10, 10, 10]); }");
    for (float t : {0.05f, 0.1f, 0.2f, 0.3f, 0.45f})
        CHECK(close(st(t, t * 0.7f, 0), stairs(t, t * 0.7f, 0.5, 3)));
    Field sti("stairs_intersection(0.5, 3) { sphere(1); translate([1, 0, 0]) sphere(1); }");
    CHECK(close(sti(0.5, 0.3f, 0), -stairs(-(std::sqrt(0.25 + 0.09) - 1), -(std::sqrt(0.25 + 0.09) - 1), 0.5, 3)));
    Field std_("stairs_difference(0.5, 3) { sphere(1); translate([1, 0, 0]) sphere(1); }");
    CHECK(std_(-0.9f, 0, 0) < 0);
    CHECK(std_(0.9f, 0, 0) > 0);
}

TEST_CASE("translate, rotate, scale, mirror") {
    CHECK(close(dist_of("translate([1, 2, 3]) sphere(1);", 1, 2, 3), -1));
    // rotate(x=, y=, z=) in degrees, x first, then y, then z.
    Field r("rotate(x = 90) translate([0, 1, 0]) sphere(0.1);");
    CHECK(close(r(0, 0, 1), -0.1));  // (0,1,0) turned 90 degrees about x goes to (0,0,1)
    Field r2("rotate(x = 90, z = 90) translate([0, 1, 0]) sphere(0.1);");
    CHECK(close(r2(0, 0, 1), -0.1));  // z rotation leaves (0,0,1) in place
    Field r3("rotate(y = 90, z = 90) translate([1, 0, 0]) sphere(0.1);");
    CHECK(close(r3(0, 0, -1), -0.1));  // y: (1,0,0) -> (0,0,-1); z leaves it
    // rotate(angle, axis)
    Field ra("rotate(90, [0, 0, 1]) translate([1, 0, 0]) sphere(0.1);");
    CHECK(close(ra(0, 1, 0), -0.1));
    Field ra2("rotate(angle = 180, axis = [1, 1, 0]) translate([1, 0, 0]) sphere(0.1);");
    CHECK(close(ra2(0, 1, 0), -0.1));
    // scale: uniform keeps the exact distance; a vector keeps a bound.
    CHECK(close(dist_of("scale(2) sphere(1);", 4, 0, 0), 2));
    Field sv("scale([2, 1, 1]) sphere(1);");
    CHECK(close(sv(2, 0, 0), 0));
    CHECK(close(sv(0, 1, 0), 0));
    CHECK(sv(4, 0, 0) <= 2.0f + 1e-5f);
    CHECK(sv(4, 0, 0) > 0);
    // mirror is an involution and reflects through the plane with the given normal.
    CHECK(close(dist_of("mirror([1, 0, 0]) translate([2, 0, 0]) sphere(1);", -2, 0, 0), -1));
    Field m2("mirror([1, 1, 0]) mirror([1, 1, 0]) translate([2, 0.5, 0]) sphere(0.3);");
    CHECK(close(m2(2, 0.5f, 0), -0.3));
}

TEST_CASE("repeat: infinite is periodic; finite stops after count; a zero period leaves the axis") {
    Field r("repeat([3, 0, 3]) sphere(0.5);");
    for_random_points(100, 4, [&](float x, float y, float z) {
        CHECK(close(r(x, y, z), r(x + 3, y, z), 1e-4));
        CHECK(close(r(x, y, z), r(x, y, z - 6), 1e-4));
    });
    CHECK(close(r(0, 3, 0), 2.5));  // y is not repeated
    Field f("repeat(2, 1) sphere(0.5);");
    CHECK(close(f(2, 2, -2), -0.5));   // index 1 on every axis: present
    CHECK(close(f(4, 0, 0), 1.5));     // index 2: absent, nearest is index 1
    Field f2("repeat([2, 0, 0], [2, 0, 0]) sphere(0.5);");
    CHECK(close(f2(-4, 0, 0), -0.5));
    CHECK(close(f2(6, 0, 0), 1.5));
    CHECK(close(f2(0, 2, 0), 1.5));
}

// A child that reaches out of its cell is whole: the copies of the neighbouring cells that
// reach into a cell are evaluated there too, so every copy is the child, not a cut piece.
TEST_CASE("repeat and polar_repeat keep copies that reach out of their cell whole") {
    auto spheres = [](float x, float y, float z, std::vector<std::array<float, 3>> cs, float r) {
        float best = 1e30f;
        for (auto& c : cs) best = std::min(best, std::sqrt((x - c[0]) * (x - c[0]) + (y - c[1]) * (y - c[1]) + (z - c[2]) * (z - c[2])) - r);
        return best;
    };
    // Finite: copies at 0.9 + 2k for k = -2..2; each spans 0.4 + 2k .. 1.4 + 2k.
    Field f("repeat([2, 0, 0], 2) translate([0.9, 0, 0]) sphere(0.5);");
    CHECK(close(f(1.3f, 0, 0), -0.1f));
    std::vector<std::array<float, 3>> fc;
    for (int k = -2; k <= 2; ++k) fc.push_back({0.9f + 2.0f * k, 0, 0});
    for_random_points(300, 6, [&](float x, float y, float z) { CHECK(close(f(x, y, z), spheres(x, y, z, fc, 0.5f), 1e-4)); });
    // Infinite, on two axes, a child across a corner of its cell.
    Field g("repeat([2, 0, 2]) translate([0.8, 0, -0.8]) sphere(0.4);");
    CHECK(close(g(1.15f, 0, -0.8f), -0.05f));
    CHECK(close(g(0.8f, 0, -1.15f), -0.05f));
    CHECK(close(g(2.8f, 0, 1.2f), -0.4f));
    // Polar: a child off copy 0's sector (+z, with 3 sectors centred on +x) is still there.
    Field p("polar_repeat(3) translate([0, 0, 2]) sphere(0.5);");
    CHECK(close(p(0, 0, 2), -0.5));
    std::vector<std::array<float, 3>> pc;
    for (int k = 0; k < 3; ++k) {
        const float a = 3.14159265f / 2 + k * 2 * 3.14159265f / 3;  // copies at angles atan2(z, x)
        pc.push_back({2 * std::cos(a), 0, 2 * std::sin(a)});
    }
    for_random_points(300, 4, [&](float x, float y, float z) { CHECK(close(p(x, y, z), spheres(x, y, z, pc, 0.5f), 1e-4)); });
}

TEST_CASE("polar_repeat is invariant under turns of 360/n about y") {
    Field p("polar_repeat(6) translate([2, 0, 0]) sphere(0.3);");
    CHECK(close(p(2, 0, 0), -0.3));
    for_random_points(100, 3, [&](float x, float y, float z) {
        float a = 3.14159265f / 3;
        float rx = std::cos(a) * x - std::sin(a) * z, rz = std::sin(a) * x + std::cos(a) * z;
        CHECK(close(p(x, y, z), p(rx, y, rz), 1e-4));
    });
}

TEST_CASE("symmetry mirrors the positive side onto the negative") {
    Field s("symmetry(x = true) translate([2, 0, 0]) sphere(0.5);");
    CHECK(close(s(-2, 0, 0), -0.5));
    CHECK(close(s(2, 0, 0), -0.5));
    Field s2("symmetry(y = true, z = true) translate([0, 1, 1]) sphere(0.5);");
    CHECK(close(s2(0, -1, -1), -0.5));
    CHECK(close(s2(0, 1, -1), -0.5));
    // LANGUAGE.md: symmetry(x=true, y=, z=). x folds unless y or z is named.
    Field s3("symmetry() translate([2, 1, 0]) sphere(0.5);");
    CHECK(close(s3(-2, 1, 0), -0.5));
    Field s4("symmetry(y = true) translate([2, 1, 0]) sphere(0.5);");
    CHECK(close(s4(2, -1, 0), -0.5));
    CHECK(close(s4(-2, 1, 0), 3.5));
}

TEST_CASE("elongate inserts a straight section of length v") {
    Field e("elongate([2, 0, 0]) sphere(1);");
    CHECK(close(e(2, 0, 0), 0));
    CHECK(close(e(0, 2, 0), 1));
    CHECK(close(e(1, 1, 0), 0));
    CHECK(close(e(3, 0, 0), 1));
}

TEST_CASE("twist and bend at rate 0 are the identity; twist turns with height") {
    for (const char* op : {"twist(0)", "bend(0)"}) {
        Field a(std::string(op) + " box([1, 2, 0.5]);");
        Field b("box([1, 2, 0.5]);");
        for_random_points(100, 2, [&](float x, float y, float z) { CHECK(close(a(x, y, z), b(x, y, z))); });
    }
    // At height y the cross-section is turned by rate * y degrees: the distance along the
    // twisted bar's long axis matches.
    Field t("twist(90) box([2, 4, 0.2]);");
    CHECK(t(0.9f, 0, 0) < 0);
    CHECK(t(0, 1, 0.9f) < 0);   // at y = 1 the long axis has turned 90 degrees onto z
    CHECK(t(0.9f, 1, 0) > 0);
}

TEST_CASE("round grows the shape, onion shells it, displace perturbs it boundedly") {
    CHECK(close(dist_of("round(0.5) box(2);", 2, 0, 0), 0.5));
    CHECK(close(dist_of("round(0.5) box(2);", 1.5, 1.5, 0), std::sqrt(0.5) - 0.5));
    CHECK(close(dist_of("onion(0.1) sphere(1);", 0, 0, 0), 0.9));
    CHECK(close(dist_of("onion(0.1) sphere(1);", 1, 0, 0), -0.1));
    CHECK(close(dist_of("onion(thickness = 0.2) sphere(1);", 1.1f, 0, 0), -0.1));
    Field d0("displace(0, 3) sphere(1);");
    CHECK(close(d0(1.5, 0.2f, 0.1f), std::sqrt(1.5 * 1.5 + 0.04 + 0.01) - 1));
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
