// Known distances of every primitive of LANGUAGE.md section 5: hand-derived values at
// chosen points, and random points against double-precision reference formulas.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <random>

#include <glm/glm.hpp>

#include "support.hpp"

using namespace sdfc;
using test::dist_of;
using dv3 = glm::dvec3;

namespace {

bool close(double got, double want) { return std::fabs(got - want) <= 1e-5 * (1 + std::fabs(want)); }

void check_random(const std::string& src, const std::function<double(dv3)>& ref, double range = 3.0, int n = 400) {
    auto c = test::compile_text(src);
    Evaluator ev(c->cs.distance);
    std::mt19937 rng(1234);
    std::uniform_real_distribution<double> u(-range, range);
    for (int i = 0; i < n; ++i) {
        dv3 p{u(rng), u(rng), u(rng)};
        // Evaluate the reference at the float point the VM sees.
        dv3 pf{float(p.x), float(p.y), float(p.z)};
        double want = ref(pf);
        double got = ev.eval1(float(p.x), float(p.y), float(p.z));
        INFO(src << " at (" << pf.x << ", " << pf.y << ", " << pf.z << "): got " << got << ", want " << want);
        REQUIRE(close(got, want));
    }
}

double len2(double a, double b) { return std::sqrt(a * a + b * b); }
double box_ref(dv3 p, dv3 half) {
    dv3 q = glm::abs(p) - half;
    return glm::length(glm::max(q, 0.0)) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
}

}  // namespace

TEST_CASE("sphere: known distances") {
    CHECK(close(dist_of("sphere(1);", 3, 0, 0), 2));
    CHECK(close(dist_of("sphere(1);", 0, 0, 0), -1));
    CHECK(close(dist_of("sphere(r = 2);", 0, 4, 0), 2));
    check_random("sphere(1.3);", [](dv3 p) { return glm::length(p) - 1.3; });
}

TEST_CASE("box: known distances") {
    CHECK(close(dist_of("box(2);", 2, 0, 0), 1));                  // face
    CHECK(close(dist_of("box(2);", 2, 2, 0), std::sqrt(2.0)));     // edge
    CHECK(close(dist_of("box(2);", 2, 2, 2), std::sqrt(3.0)));     // corner
    CHECK(close(dist_of("box(2);", 0, 0, 0), -1));                 // inside
    CHECK(close(dist_of("box([2, 4, 6]);", 0, 0, 0), -1));
    check_random("box([1, 2, 3]);", [](dv3 p) { return box_ref(p, {0.5, 1, 1.5}); });
}

TEST_CASE("round_box: keeps its full size and rounds the edges") {
    CHECK(close(dist_of("round_box(2, 0.25);", 2, 0, 0), 1));
    // Corner: the rounded corner's centre is at 0.75 on each axis.
    CHECK(close(dist_of("round_box(2, 0.25);", 2, 2, 2), std::sqrt(3 * 1.25 * 1.25) - 0.25));
    check_random("round_box([1, 2, 3], 0.2);", [](dv3 p) { return box_ref(p, dv3{0.5, 1, 1.5} - 0.2) - 0.2; });
}

TEST_CASE("box_frame: distance to the edges only") {
    // The face centre of a frame is open: the nearest edge is at distance half - e along the face.
    CHECK(close(dist_of("box_frame(2, 0.1);", 1, 0, 0), 0.9 - 0.0));
    CHECK(close(dist_of("box_frame(2, 0.1);", 2, 1, 1), 1));  // outside a corner edge, straight out
    check_random("box_frame([2, 2, 2], 0.1);", [](dv3 p) {
        dv3 b{1, 1, 1};
        double e = 0.05;  // half the bar thickness
        p = glm::abs(p) - b;
        dv3 q = glm::abs(p + e) - e;
        auto f = [](dv3 v) { return glm::length(glm::max(v, 0.0)) + std::min(std::max(v.x, std::max(v.y, v.z)), 0.0); };
        return std::min(std::min(f({p.x, q.y, q.z}), f({q.x, p.y, q.z})), f({q.x, q.y, p.z}));
    });
}

TEST_CASE("torus: in the xz-plane") {
    CHECK(close(dist_of("torus(1, 0.25);", 1, 0, 0), -0.25));
    CHECK(close(dist_of("torus(1, 0.25);", 0, 0, 0), 0.75));
    CHECK(close(dist_of("torus(major = 2, minor = 0.5);", 0, 1, 2), 0.5));
    check_random("torus(1.2, 0.3);", [](dv3 p) { return len2(len2(p.x, p.z) - 1.2, p.y) - 0.3; });
}

TEST_CASE("capped_torus: an arc of the ring in the xz-plane, symmetric about +z") {
    // 180 degrees: the half ring with z >= 0. Its ends are on the x axis.
    CHECK(close(dist_of("capped_torus(180, 1, 0.1);", 0, 0, 1), -0.1));
    // At (0,0,-1) the nearest point of the half ring is an end (±1, 0, 0): distance sqrt(2) - 0.1.
    CHECK(close(dist_of("capped_torus(180, 1, 0.1);", 0, 0, -1), std::sqrt(2.0) - 0.1));
    // A full circle (360) is the torus, also on the plane x = 0 (where sin(180 degrees) in
    // floats once flipped the branch).
    check_random("capped_torus(360, 1, 0.2);", [](dv3 p) { return len2(len2(p.x, p.z) - 1, p.y) - 0.2; });
    CHECK(close(dist_of("capped_torus(360, 2, 0.5);", 0, 0, 2), -0.5));
    CHECK(close(dist_of("capped_torus(360, 2, 0.5);", 0, 1, 2), 0.5));
    CHECK(close(dist_of("capped_torus(360, 2, 0.5);", 0, 0, -2), -0.5));
}

TEST_CASE("link: a chain link with straight sides along y") {
    CHECK(close(dist_of("link(1, 0.5, 0.1);", 0.5, 0, 0), -0.1));
    CHECK(close(dist_of("link(1, 0.5, 0.1);", 0, 1.0, 0), -0.1));  // top of the link: 0.5 + 0.5
    check_random("link(1, 0.5, 0.1);", [](dv3 p) {
        double qy = std::max(std::fabs(p.y) - 0.5, 0.0);
        return len2(len2(p.x, qy) - 0.5, p.z) - 0.1;
    });
}

TEST_CASE("cylinder: capped, along y, full height") {
    CHECK(close(dist_of("cylinder(2, 0.5);", 0, 2, 0), 1));
    CHECK(close(dist_of("cylinder(2, 0.5);", 1.5, 0, 0), 1));
    CHECK(close(dist_of("cylinder(2, 0.5);", 1.5, 2, 0), std::sqrt(2.0)));
    CHECK(close(dist_of("cylinder(h = 2, r = 0.5);", 0, 0, 0), -0.5));
    check_random("cylinder(1.5, 0.7);", [](dv3 p) {
        double dx = len2(p.x, p.z) - 0.7, dy = std::fabs(p.y) - 0.75;
        return std::min(std::max(dx, dy), 0.0) + len2(std::max(dx, 0.0), std::max(dy, 0.0));
    });
}

TEST_CASE("round_cylinder") {
    CHECK(close(dist_of("round_cylinder(2, 1, 0.2);", 0, 2, 0), 1));
    CHECK(close(dist_of("round_cylinder(2, 1, 0.2);", 2, 0, 0), 1));
    check_random("round_cylinder(2, 1, 0.2);", [](dv3 p) {
        double dx = len2(p.x, p.z) - 0.8, dy = std::fabs(p.y) - 0.8;
        return std::min(std::max(dx, dy), 0.0) + len2(std::max(dx, 0.0), std::max(dy, 0.0)) - 0.2;
    });
}

TEST_CASE("capsule: segment from a to b") {
    CHECK(close(dist_of("capsule([0, 0, 0], [0, 2, 0], 0.5);", 0, 3, 0), 0.5));
    CHECK(close(dist_of("capsule([0, 0, 0], [0, 2, 0], 0.5);", 1, 1, 0), 0.5));
    check_random("capsule([-1, 0, 0.5], [1, 1, 0], 0.3);", [](dv3 p) {
        dv3 a{-1, 0, 0.5}, b{1, 1, 0};
        double h = std::clamp(glm::dot(p - a, b - a) / glm::dot(b - a, b - a), 0.0, 1.0);
        return glm::length(p - a - (b - a) * h) - 0.3;
    });
}

TEST_CASE("cone: capped along y, base r1 at the bottom, top r2") {
    CHECK(close(dist_of("cone(2, 1);", 0, -2, 0), 1));          // below the base centre
    CHECK(close(dist_of("cone(2, 1, 0.5);", 0, 2, 0), 1));      // above the top disc
    CHECK(close(dist_of("cone(2, 1, 1);", 2, 0, 0), 1));        // r1 = r2: a cylinder
    check_random("cone(2, 1, 0.25);", [](dv3 p) {
        // Exact distance to a truncated cone by projecting onto its 2D profile polygon.
        double qx = len2(p.x, p.z), qy = p.y, h = 1, r1 = 1, r2 = 0.25;
        auto seg = [](double px, double py, double ax, double ay, double bx, double by) {
            double dx = bx - ax, dy = by - ay;
            double t = std::clamp(((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
            return len2(px - ax - dx * t, py - ay - dy * t);
        };
        double d = std::min({seg(qx, qy, 0, -h, r1, -h), seg(qx, qy, r1, -h, r2, h), seg(qx, qy, r2, h, 0, h)});
        bool inside = qy > -h && qy < h && qx < r1 + (r2 - r1) * (qy + h) / (2 * h);
        return inside ? -d : d;
    });
}

TEST_CASE("plane: the half-space below") {
    CHECK(close(dist_of("plane();", 0, 2, 0), 2));
    CHECK(close(dist_of("plane();", 5, -1, 3), -1));
    CHECK(close(dist_of("plane(normal = [0, 0, 2], offset = 1);", 0, 0, 3), 2));
    CHECK(close(dist_of("plane([1, 1, 0], 0);", 1, 1, 0), std::sqrt(2.0)));
}

TEST_CASE("ellipsoid: exact along the shortest axis, a bound elsewhere") {
    CHECK(close(dist_of("ellipsoid([1, 1, 1]);", 2, 0, 0), 1));
    CHECK(close(dist_of("ellipsoid([2, 1, 3]);", 0, 3, 0), 2));
    // Along a longer axis: (3/2 - 1) * 1 = 0.5, below the true distance 1.
    CHECK(close(dist_of("ellipsoid([2, 1, 1]);", 3, 0, 0), 0.5));
    CHECK(dist_of("ellipsoid([2, 1, 1]);", 0.5, 0, 0) < 0);
}

TEST_CASE("octahedron: exact") {
    CHECK(close(dist_of("octahedron(1);", 2, 0, 0), 1));
    CHECK(close(dist_of("octahedron(1);", 1, 1, 1), (3 - 1) / std::sqrt(3.0)));
    CHECK(close(dist_of("octahedron(1);", 0, 0, 0), -1 / std::sqrt(3.0)));
}

TEST_CASE("pyramid: base 1x1, apex h above it, centred on the origin") {
    CHECK(close(dist_of("pyramid(1);", 0, 1.5, 0), 1));     // above the apex (y = 0.5)
    CHECK(close(dist_of("pyramid(1);", 0, -1.5, 0), 1));    // below the base (y = -0.5)
    CHECK(close(dist_of("pyramid(1);", 1, -1.5, 0), std::sqrt(1.25)));  // below a base edge
    CHECK(close(dist_of("pyramid(1);", 1.5, -0.5, 0), 1.0));   // beside the base edge
    CHECK(close(dist_of("pyramid(1);", 0, -0.45, 0), -0.05)); // inside, just above the base face
    CHECK(dist_of("pyramid(1);", 0, -0.3, 0) < 0);
    CHECK(close(dist_of("pyramid(4);", 0, 2, 0), 0));        // the apex
    CHECK(close(dist_of("pyramid(4);", 0, -2, 0), 0));       // the centre of the base
}

TEST_CASE("hex_prism: along y, r is the apothem") {
    CHECK(close(dist_of("hex_prism(2, 1);", 0, 3, 0), 2));
    CHECK(close(dist_of("hex_prism(2, 1);", 0, 0, 2), 1));   // a flat side faces +z
    CHECK(close(dist_of("hex_prism(2, 1);", 0, 0, 0), -1));
}

TEST_CASE("tri_prism: along y") {
    CHECK(close(dist_of("tri_prism(2, 1);", 0, 3, 0), 2));
    CHECK(dist_of("tri_prism(2, 1);", 0, 0, 0) < 0);
}

TEST_CASE("gyroid and schwarz_p: sheets through their zero sets") {
    // The gyroid passes through the origin; Schwarz P's zero set contains (period/4, period/4, *)...
    CHECK(close(dist_of("gyroid(1, 0.1);", 0, 0, 0), -0.05));
    CHECK(close(dist_of("schwarz_p(4, 0.2);", 1, 1, 2), -0.1 + std::fabs(std::cos(M_PI / 2) * 2 + std::cos(M_PI)) * 4 / (2 * M_PI * std::sqrt(3.0))));
    check_random("gyroid(2, 0.2);", [](dv3 p) {
        double k = M_PI;
        double g = std::sin(k * p.x) * std::cos(k * p.y) + std::sin(k * p.y) * std::cos(k * p.z) + std::sin(k * p.z) * std::cos(k * p.x);
        return std::fabs(g) / (k * std::sqrt(3.0)) - 0.1;
    });
}
