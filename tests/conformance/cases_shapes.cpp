// Known distances of every primitive of LANGUAGE.md section 5: hand-derived values at
// chosen points, and random points against double-precision reference formulas.
#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "conformance/cases.hpp"

namespace sdfc::conformance {

namespace {

using dv3 = glm::dvec3;

double len2(double a, double b) { return std::sqrt(a * a + b * b); }
double box_ref(dv3 p, dv3 half) {
    dv3 q = glm::abs(p) - half;
    return glm::length(glm::max(q, 0.0)) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
}
// A reference written for a dvec3 point.
template <class F>
ShapeCases::Ref ref3(F f) {
    return [f](double x, double y, double z) { return f(dv3{x, y, z}); };
}

}  // namespace

void add_primitive_cases(std::vector<Case>& out) {
    ShapeCases s(out);

    s.script("sphere(1);").at(3, 0, 0, 2).at(0, 0, 0, -1);
    s.script("sphere(r = 2);").at(0, 4, 0, 2);
    s.script("sphere(1.3);").random(ref3([](dv3 p) { return glm::length(p) - 1.3; }));

    s.script("box(2);")
        .at(2, 0, 0, 1)                  // face
        .at(2, 2, 0, std::sqrt(2.0))     // edge
        .at(2, 2, 2, std::sqrt(3.0))     // corner
        .at(0, 0, 0, -1);                // inside
    s.script("box([2, 4, 6]);").at(0, 0, 0, -1);
    s.script("box([1, 2, 3]);").random(ref3([](dv3 p) { return box_ref(p, {0.5, 1, 1.5}); }));

    // round_box keeps its full size and rounds the edges; the rounded corner's centre is at 0.75.
    s.script("round_box(2, 0.25);").at(2, 0, 0, 1).at(2, 2, 2, std::sqrt(3 * 1.25 * 1.25) - 0.25);
    s.script("round_box([1, 2, 3], 0.2);").random(ref3([](dv3 p) { return box_ref(p, dv3{0.5, 1, 1.5} - 0.2) - 0.2; }));
    // A radius over half the smallest side is that half: the full size is kept (a cube
    // becomes a sphere).
    s.script("round_box(2, 1.5);").at(1, 0, 0, 0).at(2, 0, 0, 1).at(0, 0, 0, -1).at(2, 2, 2, std::sqrt(12.0) - 1);
    s.script("round_box([1, 2, 3], 0.9);").random(ref3([](dv3 p) { return box_ref(p, dv3{0.5, 1, 1.5} - 0.5) - 0.5; }));

    // box_frame: distance to the edges only. The face centre of a frame is open: the nearest
    // edge is at distance half - e along the face.
    s.script("box_frame(2, 0.1);").at(1, 0, 0, 0.9).at(2, 1, 1, 1);  // outside a corner edge, straight out
    // Bars thicker than half the box fill it: the box (its outside exact, inside a bound).
    s.script("box_frame(1, 0.6);").at(0.7f, 0, 0, 0.2f, 1e-5).at(0.7f, 0.7f, 0, 0.2828427f, 1e-5).at(0.4f, 0.4f, 0.4f, -0.1f, 1e-5);
    s.script("box_frame([2, 2, 2], 0.1);").random(ref3([](dv3 p) {
        dv3 b{1, 1, 1};
        double e = 0.05;  // half the bar thickness
        p = glm::abs(p) - b;
        dv3 q = glm::abs(p + e) - e;
        auto f = [](dv3 v) { return glm::length(glm::max(v, 0.0)) + std::min(std::max(v.x, std::max(v.y, v.z)), 0.0); };
        return std::min(std::min(f({p.x, q.y, q.z}), f({q.x, p.y, q.z})), f({q.x, q.y, p.z}));
    }));

    // torus: in the xz-plane.
    s.script("torus(1, 0.25);").at(1, 0, 0, -0.25).at(0, 0, 0, 0.75);
    s.script("torus(major = 2, minor = 0.5);").at(0, 1, 2, 0.5);
    s.script("torus(1.2, 0.3);").random(ref3([](dv3 p) { return len2(len2(p.x, p.z) - 1.2, p.y) - 0.3; }));

    // capped_torus: an arc of the ring in the xz-plane, symmetric about +z. 180 degrees: the
    // half ring with z >= 0, its ends on the x axis; at (0,0,-1) the nearest point is an end.
    s.script("capped_torus(180, 1, 0.1);").at(0, 0, 1, -0.1).at(0, 0, -1, std::sqrt(2.0) - 0.1);
    // A full circle (360) is the torus, also on the plane x = 0 (where sin(180 degrees) in
    // floats once flipped the branch).
    s.script("capped_torus(360, 1, 0.2);").random(ref3([](dv3 p) { return len2(len2(p.x, p.z) - 1, p.y) - 0.2; }));
    s.script("capped_torus(360, 2, 0.5);").at(0, 0, 2, -0.5).at(0, 1, 2, 0.5).at(0, 0, -2, -0.5);

    // link: a chain link with straight sides along y; the top of the link is at 0.5 + 0.5.
    s.script("link(1, 0.5, 0.1);").at(0.5, 0, 0, -0.1).at(0, 1.0, 0, -0.1).random(ref3([](dv3 p) {
        double qy = std::max(std::fabs(p.y) - 0.5, 0.0);
        return len2(len2(p.x, qy) - 0.5, p.z) - 0.1;
    }));

    // cylinder: capped, along y, full height.
    s.script("cylinder(2, 0.5);").at(0, 2, 0, 1).at(1.5, 0, 0, 1).at(1.5, 2, 0, std::sqrt(2.0));
    s.script("cylinder(h = 2, r = 0.5);").at(0, 0, 0, -0.5);
    s.script("cylinder(1.5, 0.7);").random(ref3([](dv3 p) {
        double dx = len2(p.x, p.z) - 0.7, dy = std::fabs(p.y) - 0.75;
        return std::min(std::max(dx, dy), 0.0) + len2(std::max(dx, 0.0), std::max(dy, 0.0));
    }));

    s.script("round_cylinder(2, 1, 2);").at(0, 2, 0, 1).at(2, 0, 0, 1).at(0, 0, 0, -1);  // edge at most r and h / 2
    s.script("round_cylinder(2, 1, 0.2);").at(0, 2, 0, 1).at(2, 0, 0, 1).random(ref3([](dv3 p) {
        double dx = len2(p.x, p.z) - 0.8, dy = std::fabs(p.y) - 0.8;
        return std::min(std::max(dx, dy), 0.0) + len2(std::max(dx, 0.0), std::max(dy, 0.0)) - 0.2;
    }));

    // capsule: the segment from a to b.
    s.script("capsule([0, 0, 0], [0, 2, 0], 0.5);").at(0, 3, 0, 0.5).at(1, 1, 0, 0.5);
    s.script("capsule([-1, 0, 0.5], [1, 1, 0], 0.3);").random(ref3([](dv3 p) {
        dv3 a{-1, 0, 0.5}, b{1, 1, 0};
        double h = std::clamp(glm::dot(p - a, b - a) / glm::dot(b - a, b - a), 0.0, 1.0);
        return glm::length(p - a - (b - a) * h) - 0.3;
    }));

    // cone: capped along y, base r1 at the bottom, top r2.
    s.script("cone(2, 1);").at(0, -2, 0, 1);          // below the base centre
    s.script("cone(2, 1, 0.5);").at(0, 2, 0, 1);      // above the top disc
    s.script("cone(2, 1, 1);").at(2, 0, 0, 1);        // r1 = r2: a cylinder
    s.script("cone(0, 1, 1);").at(0, 0.5, 0, 0.5).at(2, 0, 0, 1).at(0.5, -0.25, 0, 0.25);  // a flat disc (was 0/0)
    s.script("cone(2, 1, 0.25);").random(ref3([](dv3 p) {
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
    }));

    // plane: the half-space below.
    s.script("plane();").at(0, 2, 0, 2).at(5, -1, 3, -1);
    s.script("plane(normal = [0, 0, 2], offset = 1);").at(0, 0, 3, 2);
    s.script("plane([1, 1, 0], 0);").at(1, 1, 0, std::sqrt(2.0));

    // ellipsoid: exact along the shortest axis, a bound elsewhere. Along a longer axis:
    // (3/2 - 1) * 1 = 0.5, below the true distance 1.
    s.script("ellipsoid([1, 1, 1]);").at(2, 0, 0, 1);
    s.script("ellipsoid([2, 1, 3]);").at(0, 3, 0, 2);
    s.script("ellipsoid([2, 1, 1]);").at(3, 0, 0, 0.5).less(0.5, 0, 0, 0);

    s.script("octahedron(1);").at(2, 0, 0, 1).at(1, 1, 1, (3 - 1) / std::sqrt(3.0)).at(0, 0, 0, -1 / std::sqrt(3.0));

    // pyramid: base 1x1, apex h above it, centred on the origin.
    s.script("pyramid(1);")
        .at(0, 1.5, 0, 1)                  // above the apex (y = 0.5)
        .at(0, -1.5, 0, 1)                 // below the base (y = -0.5)
        .at(1, -1.5, 0, std::sqrt(1.25))   // below a base edge
        .at(1.5, -0.5, 0, 1.0)             // beside the base edge
        .at(0, -0.45f, 0, -0.05)           // inside, just above the base face
        .less(0, -0.3f, 0, 0);
    s.script("pyramid(4);").at(0, 2, 0, 0).at(0, -2, 0, 0);  // the apex, the centre of the base

    // 2D profiles (an extension): prisms along z; extrude and revolve make solids of them.
    s.script("circle(1);").at(2, 0, 5, 1).at(0, 0, -7, -1);
    s.script("square([2, 1]);").at(2, 0, 3, 1).at(0, 1.5, 0, 1);
    s.script("extrude(2) circle(1);").at(0, 0, 0, -1).at(0, 0, 1.5, 0.5).at(1.5, 0, 1.5, std::sqrt(0.5));
    s.script("extrude(1) square([2, 1]);").at(0, 0, 0, -0.5).at(2, 0, 0, 1);
    s.script("revolve(2) circle(0.5);").at(2, 0, 0, -0.5).at(0, 0, 2, -0.5).at(0, 0, 0, 1.5).at(2, 1, 0, 0.5);
    s.script("revolve() translate([1, 0, 0]) square(0.5);").at(1, 0, 0, -0.25).at(0, 1, 1, 0.75);
    s.script("polygon([[0, 0], [2, 0], [0, 2]]);").at(0.5, 0.5, 0, -0.5).at(3, 0, 0, 1).at(-1, -1, 3, std::sqrt(2.0)).at(1, 1, 0, 0);
    s.script("revolve() polygon([[0.5, -1], [1, -1], [1, 1], [0.5, 1]]);").at(0.75, 0, 0, -0.25).at(0, 0, 0, 0.5).at(0, 2, 0.75, 1);
    // A concave outline (an L) and its notch.
    s.script("polygon([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]);").at(0.5, 0.5, 0, -0.5).at(1.5, 1.5, 0, 0.5).at(0.5, 1.5, 0, -0.5).at(3, 3, 0, std::sqrt(5.0));

    // hex_prism: along y, r is the apothem; a flat side faces +z.
    s.script("hex_prism(2, 1);").at(0, 3, 0, 2).at(0, 0, 2, 1).at(0, 0, 0, -1);
    s.script("tri_prism(2, 1);").at(0, 3, 0, 2).less(0, 0, 0, 0);

    // gyroid and schwarz_p: sheets through their zero sets. The gyroid passes through the
    // origin; Schwarz P's zero set contains (period/4, period/4, *).
    s.script("gyroid(1, 0.1);").at(0, 0, 0, -0.05);
    s.script("schwarz_p(4, 0.2);")
        .at(1, 1, 2, -0.1 + std::fabs(std::cos(M_PI / 2) * 2 + std::cos(M_PI)) * 4 / (2 * M_PI * std::sqrt(3.0)));
    s.script("gyroid(2, 0.2);").random(ref3([](dv3 p) {
        double k = M_PI;
        double g = std::sin(k * p.x) * std::cos(k * p.y) + std::sin(k * p.y) * std::cos(k * p.z) + std::sin(k * p.z) * std::cos(k * p.x);
        return std::fabs(g) / (k * std::sqrt(3.0)) - 0.1;
    }));
}

}  // namespace sdfc::conformance
