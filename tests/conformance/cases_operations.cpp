// Every operation of LANGUAGE.md section 6: a known distance, a sign, or a reference formula
// at random points. (Properties relating two evaluations, such as periodicity, stay in
// tests/compiler/test_operations.cpp.)
#include <algorithm>
#include <array>
#include <cmath>

#include "conformance/cases.hpp"
#include "support.hpp"

namespace sdfc::conformance {

namespace {

double sph(double x, double y, double z, double cx, double r) { return std::sqrt((x - cx) * (x - cx) + y * y + z * z) - r; }

// The nearest of spheres of radius r at the given centres.
ShapeCases::Ref spheres(std::vector<std::array<double, 3>> cs, double r) {
    return [cs, r](double x, double y, double z) {
        double best = 1e30;
        for (auto& c : cs) best = std::min(best, std::sqrt((x - c[0]) * (x - c[0]) + (y - c[1]) * (y - c[1]) + (z - c[2]) * (z - c[2])) - r);
        return best;
    };
}

double stairs(double a, double b, double r, double n) {
    double s = r / n, u = b - r;
    double m = (u - a + s) - 2 * s * std::floor((u - a + s) / (2 * s));
    return std::min(std::min(a, b), 0.5 * (u + a + std::fabs(m - s)));
}

}  // namespace

void add_operation_cases(std::vector<Case>& out) {
    ShapeCases s(out);

    // union, intersection, difference, xor of two unit spheres 1.5 apart.
    s.script("union { sphere(1); translate([1.5, 0, 0]) sphere(1); }")
        .random([](double x, double y, double z) { return std::min(sph(x, y, z, 0, 1), sph(x, y, z, 1.5, 1)); }, 3, 200);
    s.script("intersection { sphere(1); translate([1.5, 0, 0]) sphere(1); }")
        .random([](double x, double y, double z) { return std::max(sph(x, y, z, 0, 1), sph(x, y, z, 1.5, 1)); }, 3, 200);
    s.script("difference { sphere(1); translate([1.5, 0, 0]) sphere(1); }")
        .random([](double x, double y, double z) { return std::max(sph(x, y, z, 0, 1), -sph(x, y, z, 1.5, 1)); }, 3, 200);
    s.script("xor { sphere(1); translate([1.5, 0, 0]) sphere(1); }").random([](double x, double y, double z) {
        const double a = sph(x, y, z, 0, 1), b = sph(x, y, z, 1.5, 1);
        return std::max(std::min(a, b), -std::max(a, b));
    }, 3, 200);
    // Difference takes the first minus all the rest.
    s.script("difference { box(4); sphere(1); translate([0, 0, 2]) sphere(1); }").greater(0, 0, 0, 0).greater(0, 0, 2, 0).less(1.5, 1.5, 0, 0);

    // A for statement in a CSG block is one operand, the union of its iterations
    // (LANGUAGE.md section 4; as in OpenSCAD).
    s.script("difference {\n for (x = [-1, 1]) translate([x, 0, 0]) sphere(0.5);\n sphere(0.2);\n}").at(1, 0, 0, -0.5).at(-1, 0, 0, -0.5).at(0, 0, 0, 0.5);
    s.script("intersection { for (x = [-1, 1]) translate([x * 0.5, 0, 0]) sphere(1); box(10); }").at(1.4f, 0, 0, -0.1f);
    // ... but a loop alone in an intersection gives its iterations (OpenSCAD's intersection_for).
    s.script("intersection { for (x = [-1, 1]) translate([x * 0.5, 0, 0]) sphere(1); }").at(0, 0, 0, -0.5f).greater(1.4f, 0, 0, 0);
    s.script("smooth_intersection(0.1) { for (x = [-1, 1]) translate([x * 0.5, 0, 0]) sphere(1); }").greater(1.4f, 0, 0, 0);
    // Cut by a loop: the rest of a difference may be a loop too.
    s.script("difference { box(4); for (z = [-1, 1]) translate([0, 0, z]) sphere(0.5); }").at(0, 0, 1, 0.5).less(0, 0, 0, 0);
    // A lone loop is the first operand and nothing is subtracted.
    s.script("difference { for (x = [-1, 1]) translate([x, 0, 0]) sphere(0.5); }").at(1, 0, 0, -0.5).at(-1, 0, 0, -0.5);
    // Union-like blocks take the iterations as operands: a smooth union blends them.
    s.script("union { for (x = [-1, 1]) translate([x, 0, 0]) sphere(0.8); sphere(0.1); }").at(0, 1, 0, std::sqrt(2.0f) - 0.8f);
    s.script("smooth_union(1) { for (x = [-1, 1]) translate([x, 0, 0]) sphere(0.8); sphere(0.1); }").less(0, 1, 0, std::sqrt(2.0f) - 0.8f - 0.1f);

    // Smooth operations equal the hard ones beyond k and blend within: where both distances
    // are equal the quadratic smin lowers the union by k/4.
    s.script("smooth_union(0.5) { sphere(1); translate([3, 0, 0]) sphere(1); }")
        .at(-2, 0, 0, 1)
        .at(1.5, 0, 0, 0.5 - 0.125)
        .random_bound([](double x, double y, double z) { return std::min(sph(x, y, z, 0, 1), sph(x, y, z, 3, 1)); },
                      [](double x, double y, double z) { return std::fabs(sph(x, y, z, 0, 1) - sph(x, y, z, 3, 1)) <= 0.5; }, 2e-6, 3, 300, 99);
    s.script("smooth_intersection(0.5) { sphere(1); translate([1, 0, 0]) sphere(1); }").at(-1, 0, 0, 1).at(0.5, 0, 0, -0.5 + 0.125);
    // Difference: b's inside carved out; at a == -b the blend raises by k/4.
    s.script("smooth_difference(0.5) { sphere(1); translate([1, 0, 0]) sphere(1); }").at(0, 0, 0, 0).at(-0.5, 0, 0, -0.5 + 0.125);

    // Chamfer and stairs follow hg_sdf (chamfer's diagonal halved: same surface, 1-Lipschitz).
    // Two boxes meeting at a right angle (x < 0 and y < 0 solids): the chamfer cuts the corner.
    s.script("chamfer_union(0.4) { translate([-5, 0, 0]) box([10, 10, 10]); translate([0, -5, 0]) box([10, 10, 10]); }")
        .at(0.3f, 0.3f, 0, std::min(0.3, (0.3 + 0.3 - 0.4) * 0.5))
        .at(3, 3, 0, (3 + 3 - 0.4) * 0.5);  // a bound there: below the true 3
    s.script("chamfer_intersection(0.4) { box(2); translate([0.5, 0, 0]) box(2); }").at(0, 0, 0, std::max({-1.0, -0.5, (-1 - 0.5 + 0.4) * 0.5}));
    s.script("chamfer_difference(0.4) { box(2); translate([2, 0, 0]) box(2); }").greater(0.95f, 0.95f, 0, -0.05f);
    s.script("stairs_union(0.5, 3) { translate([-5, 0, 0]) box([10, 10, 10]); translate([0, -5, 0]) box([10, 10, 10]); }");
    for (float t : {0.05f, 0.1f, 0.2f, 0.3f, 0.45f}) s.at(t, t * 0.7f, 0, stairs(t, t * 0.7f, 0.5, 3));
    s.script("stairs_intersection(0.5, 3) { sphere(1); translate([1, 0, 0]) sphere(1); }")
        .at(0.5, 0.3f, 0, -stairs(-(std::sqrt(0.25 + 0.09) - 1), -(std::sqrt(0.25 + 0.09) - 1), 0.5, 3));
    s.script("stairs_difference(0.5, 3) { sphere(1); translate([1, 0, 0]) sphere(1); }").less(-0.9f, 0, 0, 0).greater(0.9f, 0, 0, 0);
    // No size: the hard operations (as smooth and chamfer), not steps of width 0 (NaN).
    s.script("stairs_union(0, 3) { box(2); translate([0, 1.5, 0]) box(1); }").at(0, 0, 0, -1).at(0, 1.5f, 0, -0.5f).at(3, 0, 0, 2);
    s.script("stairs_intersection(0, 3) { box(2); translate([0.5, 0, 0]) box(2); }").at(0, 0, 0, -0.5f);
    s.script("stairs_difference(0, 3) { box(2); translate([2, 0, 0]) box(2); }").at(-0.5f, 0, 0, -0.5f);

    // translate, rotate, scale, mirror. rotate(x=, y=, z=) in degrees, x first, then y, then z.
    s.script("translate([1, 2, 3]) sphere(1);").at(1, 2, 3, -1);
    s.script("rotate(x = 90) translate([0, 1, 0]) sphere(0.1);").at(0, 0, 1, -0.1);  // (0,1,0) turned about x goes to (0,0,1)
    s.script("rotate(x = 90, z = 90) translate([0, 1, 0]) sphere(0.1);").at(0, 0, 1, -0.1);  // z leaves (0,0,1) in place
    s.script("rotate(y = 90, z = 90) translate([1, 0, 0]) sphere(0.1);").at(0, 0, -1, -0.1);  // y: (1,0,0) -> (0,0,-1)
    s.script("rotate(90, [0, 0, 1]) translate([1, 0, 0]) sphere(0.1);").at(0, 1, 0, -0.1);
    s.script("rotate(angle = 180, axis = [1, 1, 0]) translate([1, 0, 0]) sphere(0.1);").at(0, 1, 0, -0.1);
    // scale: uniform keeps the exact distance; a vector keeps a bound.
    s.script("scale(2) sphere(1);").at(4, 0, 0, 2);
    s.script("scale([2, 1, 1]) sphere(1);").at(2, 0, 0, 0).at(0, 1, 0, 0).less(4, 0, 0, 2.0f + 1e-5f).greater(4, 0, 0, 0);
    // mirror is an involution and reflects through the plane with the given normal.
    s.script("mirror([1, 0, 0]) translate([2, 0, 0]) sphere(1);").at(-2, 0, 0, -1);
    s.script("mirror([1, 1, 0]) mirror([1, 1, 0]) translate([2, 0.5, 0]) sphere(0.3);").at(2, 0.5f, 0, -0.3);

    // repeat: finite stops after count; a zero period leaves the axis.
    s.script("repeat([3, 0, 3]) sphere(0.5);").at(0, 3, 0, 2.5);  // y is not repeated
    s.script("repeat(2, 1) sphere(0.5);").at(2, 2, -2, -0.5).at(4, 0, 0, 1.5);  // index 1 present, index 2 absent
    s.script("repeat([2, 0, 0], [2, 0, 0]) sphere(0.5);").at(-4, 0, 0, -0.5).at(6, 0, 0, 1.5).at(0, 2, 0, 1.5);
    s.script("repeat([2, 0, 0], [1.5, 0, 0]) sphere(0.5);").at(2, 0, 0, -0.5).at(3, 0, 0, 0.5);  // a count is whole: 1.5 is 1

    // Cells are centred on the child: an off-centre child is whole, and a point by its cell's
    // face sees the copy next door (-0.99: the copy at -1.15, not its own at 0.85). The copies
    // left out are a floor under the distance: exact near the surface, a bound further out.
    // Finite: copies at 0.9 + 2k for k = -2..2.
    std::vector<std::array<double, 3>> fc;
    for (int k = -2; k <= 2; ++k) fc.push_back({0.9 + 2.0 * k, 0, 0});
    const auto far = [](const ShapeCases::Ref& ref) { return [ref](double x, double y, double z) { return ref(x, y, z) > 0.3; }; };
    s.script("repeat([2, 0, 0], 2) translate([0.9, 0, 0]) sphere(0.5);", 6).at(1.3f, 0, 0, -0.1f).random_bound(spheres(fc, 0.5), far(spheres(fc, 0.5)), 1e-4, 6, 300, 99, 1e-4);
    // A child of two parts (no sphere alone: the floor is in its program), copies at 3k.
    std::vector<std::array<double, 3>> big, small;
    for (int k = -3; k <= 3; ++k) big.push_back({0.9 + 3.0 * k, 0, 0}), small.push_back({-0.3 + 3.0 * k, 0, 0});
    const ShapeCases::Ref two = [big, small](double x, double y, double z) {
        return std::min(spheres(big, 0.3)(x, y, z), spheres(small, 0.2)(x, y, z));
    };
    s.script("repeat([3, 0, 0]) union { translate([0.9, 0, 0]) sphere(0.3); translate([-0.3, 0, 0]) sphere(0.2); }", 4)
        .at(-1.95f, 0, 0, -0.15f, 1e-4)  // inside the big sphere at -2.1
        .random_bound(two, far(two), 1e-4, 4, 300, 7, 1e-4);
    s.script("repeat([2, 0, 0]) translate([0.85, 0, 0]) sphere(0.1);").at(-0.99f, 0, 0, 0.06f, 1e-4).at(0.85f, 0.5f, 0, 0.4f);
    s.script("repeat([2, 0, 0]) translate([0.45, 0, 0]) sphere(0.5);").at(-0.62f, 0, 0, 0.43f, 1e-4);
    // Infinite, on two axes, a child across a corner of its cell.
    s.script("repeat([2, 0, 2]) translate([0.8, 0, -0.8]) sphere(0.4);").at(1.15f, 0, -0.8f, -0.05f).at(0.8f, 0, -1.15f, -0.05f).at(2.8f, 0, 1.2f, -0.4f);
    // Polar: a child off copy 0's sector (+z, with 3 sectors centred on +x) is still there.
    std::vector<std::array<double, 3>> pc;
    for (int k = 0; k < 3; ++k) {
        const double a = M_PI / 2 + k * 2 * M_PI / 3;  // copies at angles atan2(z, x)
        pc.push_back({2 * std::cos(a), 0, 2 * std::sin(a)});
    }
    s.script("polar_repeat(3) translate([0, 0, 2]) sphere(0.5);", 4).at(0, 0, 2, -0.5).random_bound(spheres(pc, 0.5), far(spheres(pc, 0.5)), 1e-4, 4, 300, 99, 1e-4);
    // Sectors centred on an off-centre child: the copy next door is seen past the sector's edge.
    s.script("polar_repeat(4) translate([1, 0, 0.5]) sphere(0.2);").at(0.764f, 0.05f, 0.791f, 0.17799f, 1e-4);
    std::vector<std::array<double, 3>> pa, pb;
    for (int k = 0; k < 4; ++k) {
        const double a = k * M_PI / 2;  // copy k turned by k quarter turns: (x, z) -> (x cos - z sin, x sin + z cos)
        pa.push_back({1.0 * std::cos(a) - 0.5 * std::sin(a), 0, 1.0 * std::sin(a) + 0.5 * std::cos(a)});
        pb.push_back({1.5 * std::cos(a), 0, 1.5 * std::sin(a)});
    }
    const ShapeCases::Ref pair = [pa, pb](double x, double y, double z) {
        return std::min(spheres(pa, 0.2)(x, y, z), spheres(pb, 0.1)(x, y, z));
    };
    s.script("polar_repeat(4) union { translate([1, 0, 0.5]) sphere(0.2); translate([1.5, 0, 0]) sphere(0.1); }", 3)
        .random_bound(pair, far(pair), 1e-4, 3, 300, 7, 1e-4);
    s.script("polar_repeat(6) translate([2, 0, 0]) sphere(0.3);").at(2, 0, 0, -0.3);
    // A count from a param is whole, the part after the point dropped (2.5: two copies).
    s.script("let n = param(2.5, 1, 10);\npolar_repeat(n) translate([1, 0, 0]) sphere(0.2);").at(-1, 0, 0, -0.2f, 1e-5).at(0, 0, 1, 1.2142136f, 1e-5);
    // The copies left out are no nearer than their ring: on the axis a box's copies are 1.75
    // away (the floor r sin(d) alone was 0 there, and rays along the axis drew a line).
    s.script("polar_repeat(4) translate([2, 0, 0]) box(0.5);").at(0, 0, 0, 1.75f, 1e-5).at(0, 0.3f, 0, 1.7507142f, 1e-5).at(1e-6f, 0, 0, 1.75f, 1e-5);
    // A smooth union of 8 or more operands blends through a select (the same floats): ten
    // spheres in a row against Quilez's chain in doubles.
    s.script("smooth_union(0.3) { for (i = [0 : 9]) translate([i * 0.5 - 2.25, 0, 0]) sphere(0.2); }", 3)
        .random([](double x, double y, double z) {
            double acc = sph(x, y, z, -2.25, 0.2);
            for (int i = 1; i < 10; ++i) {
                const double b = sph(x, y, z, i * 0.5 - 2.25, 0.2), h = std::max(0.3 - std::fabs(acc - b), 0.0) / 0.3;
                acc = std::min(acc, b) - h * h * 0.3 * 0.25;
            }
            return acc;
        }, 3, 300, 1e-5, 11);
    // A blend size at or below 0 is the hard operation, also when it is known only as the
    // program runs (a param: in GLSL a uniform; 0 / 0 was NaN there, and the shader drew nothing).
    s.script("let k = param(0, 0, 1);\nsmooth_union(k) { translate([-0.5, 0, 0]) sphere(0.5); translate([0.5, 0, 0]) box(0.8); }")
        .at(0, 0, 0, 0).at(0, 1, 0, 0.6082763f, 1e-5).at(-1.5f, 0, 0, 0.5f, 1e-5);
    s.script("let k = param(0, 0, 1);\nsmooth_difference(k) { box(1); sphere(0.6); }").at(0, 0, 0, 0.6f, 1e-5).at(0.5f, 0.5f, 0.5f, 0, 1e-5);
    s.script("smooth_union(-0.2) { sphere(1); translate([1.5, 0, 0]) sphere(1); }").at(0.75f, 0, 0, -0.25f, 1e-5);
    // A child that a param moves (in GLSL a uniform; here at its default): the cells move with
    // it, so its copies are whole (they were cut at the faces of cells laid out for 0).
    std::vector<std::array<double, 3>> mc;
    for (int k = -3; k <= 3; ++k) mc.push_back({0.6 + 1.5 * k, 0, 0});
    s.script("let off = param(0.6, 0, 1);\nrepeat([1.5, 0, 0]) translate([off, 0, 0]) sphere(0.35);", 4)
        .at(0.85f, 0, 0, -0.1f, 1e-4)
        .random_bound(spheres(mc, 0.35), far(spheres(mc, 0.35)), 1e-4, 4, 300, 5, 1e-4);
    // A param's rotation keeps the child within its radius: the neighbouring sectors' copies
    // are evaluated (the copy at -30 degrees reaches past its sector's edge at -36), and it
    // gives what the same turn written as a constant gives.
    std::shared_ptr<const test::Compiled> turned(test::compile_text("polar_repeat(5) rotate(y = 30) translate([1, 0, 0]) sphere(0.3);"));
    s.script("let turn = param(30, 0, 90);\npolar_repeat(5) rotate(y = turn) translate([1, 0, 0]) sphere(0.3);", 2)
        .at(float(std::cos(-40 * M_PI / 180)), 0, float(std::sin(-40 * M_PI / 180)), 2 * std::sin(5 * M_PI / 180) - 0.3, 1e-4)
        .random([turned](double x, double y, double z) { return double(test::dist(turned->cs, float(x), float(y), float(z))); }, 2, 300,
                1e-4, 5);

    // symmetry mirrors the positive side onto the negative; x folds unless y or z is named.
    s.script("symmetry(x = true) translate([2, 0, 0]) sphere(0.5);").at(-2, 0, 0, -0.5).at(2, 0, 0, -0.5);
    s.script("symmetry(y = true, z = true) translate([0, 1, 1]) sphere(0.5);").at(0, -1, -1, -0.5).at(0, 1, -1, -0.5);
    s.script("symmetry() translate([2, 1, 0]) sphere(0.5);").at(-2, 1, 0, -0.5);
    s.script("symmetry(y = true) translate([2, 1, 0]) sphere(0.5);").at(2, -1, 0, -0.5).at(-2, 1, 0, 3.5);

    // elongate inserts a straight section of length v.
    s.script("elongate([2, 0, 0]) sphere(1);").at(2, 0, 0, 0).at(0, 2, 0, 1).at(1, 1, 0, 0).at(3, 0, 0, 1);

    // twist and bend at rate 0 are the identity (the box's own distance).
    const auto box_ref = [](double x, double y, double z) {
        const double qx = std::fabs(x) - 0.5, qy = std::fabs(y) - 1, qz = std::fabs(z) - 0.25;
        const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0), oz = std::max(qz, 0.0);
        return std::sqrt(ox * ox + oy * oy + oz * oz) + std::min(std::max(qx, std::max(qy, qz)), 0.0);
    };
    s.script("twist(0) box([1, 2, 0.5]);").random(box_ref, 2, 100, 1e-5, 99);
    s.script("bend(0) box([1, 2, 0.5]);").random(box_ref, 2, 100, 1e-5, 98);
    // At height y the cross-section is turned by rate * y degrees: at y = 1 the long axis has
    // turned 90 degrees onto z.
    s.script("twist(90) box([2, 4, 0.2]);").less(0.9f, 0, 0, 0).less(0, 1, 0.9f, 0).greater(0.9f, 1, 0, 0);

    // round grows the shape, onion shells it; displace with amplitude 0 is the shape.
    s.script("round(0.5) box(2);").at(2, 0, 0, 0.5).at(1.5, 1.5, 0, std::sqrt(0.5) - 0.5);
    s.script("onion(0.1) sphere(1);").at(0, 0, 0, 0.9).at(1, 0, 0, -0.1);
    s.script("onion(thickness = 0.2) sphere(1);").at(1.1f, 0, 0, -0.1);
    s.script("displace(0, 3) sphere(1);").at(1.5, 0.2f, 0.1f, std::sqrt(1.5 * 1.5 + 0.04 + 0.01) - 1);
}

}  // namespace sdfc::conformance
