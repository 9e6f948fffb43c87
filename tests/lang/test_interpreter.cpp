// The interpreter: lets, defs, loops, conditionals, vectors and shapes, checked through the
// distances of the scenes they build.
#include <catch2/catch.hpp>

#include <cmath>

#include "support.hpp"

using namespace sdfc;
using test::dist_of;

namespace {
bool close(double got, double want) { return std::fabs(got - want) <= 1e-5 * (1 + std::fabs(want)); }
}  // namespace

TEST_CASE("let binds constants") {
    CHECK(close(dist_of("let r = 0.5; sphere(r);", 1, 0, 0), 0.5));
    CHECK(close(dist_of("let a = 2; let b = a * 3 + 1; sphere(b);", 0, 0, 0), -7));
}

TEST_CASE("def returns shapes and values, with defaults and named arguments") {
    const char* ring = "def ring(R, t = 0.1) = rotate(x = 90) torus(R, t);\n";
    CHECK(close(dist_of(std::string(ring) + "ring(2);", 2, 0, 0), -0.1));
    CHECK(close(dist_of(std::string(ring) + "ring(2);", 0, 2, 0), -0.1));  // now in the xy-plane
    CHECK(close(dist_of(std::string(ring) + "ring(t = 0.5, R = 1);", 1, 0, 0), -0.5));
    CHECK(close(dist_of("def lerp3(a, b, k) = a + (b - a) * k; sphere(lerp3(1, 3, 0.5));", 0, 0, 0), -2));
    CHECK(close(dist_of("def pair() = { sphere(1); translate([3, 0, 0]) box(1); }; pair();", 3, 0, 0), -0.5));
}

TEST_CASE("defs may be used before the line that defines them") {
    CHECK(close(dist_of("thing();\ndef thing() = sphere(2);", 0, 0, 0), -2));
}

TEST_CASE("for unions its iterations, nested bindings, vectors") {
    const char* ring = "for (i = [0 : 7]) rotate(y = 45 * i) translate([2, 0, 0]) sphere(0.2);";
    CHECK(close(dist_of(ring, 2, 0, 0), -0.2));
    CHECK(close(dist_of(ring, 0, 0, 2), -0.2));
    CHECK(close(dist_of(ring, std::sqrt(2.0), 0, std::sqrt(2.0)), -0.2));
    const char* grid = "for (x = [0 : 2], z = [0 : 2]) translate([x, 0, z]) box(0.4);";
    CHECK(close(dist_of(grid, 2, 0, 2), -0.2));
    CHECK(close(dist_of(grid, 1, 0, 0), -0.2));
    CHECK(close(dist_of(grid, 3, 0, 0), 0.8));
    CHECK(close(dist_of("for (s = [-1, 1]) translate([s * 2, 0, 0]) sphere(0.5);", -2, 0, 0), -0.5));
    CHECK(close(dist_of("for (i = [0 : 0.5 : 1]) translate([i * 4, 0, 0]) sphere(0.1);", 2, 0, 0), -0.1));
    CHECK(close(dist_of("for (p = [[1, 0, 0], [0, 5, 0]]) translate(p) sphere(0.5);", 0, 5, 0), -0.5));
}

TEST_CASE("a range with a fractional step keeps its end, however many steps") {
    // 0.1f is a little over a tenth: [0 : 0.1 : 10] used to stop at 9.9 (100 elements).
    CHECK(close(dist_of("sphere(len([0 : 0.1 : 10]));", 0, 0, 0), -101));
    CHECK(close(dist_of("sphere(len([10 : -0.1 : 0]));", 0, 0, 0), -101));
    CHECK(close(dist_of("sphere(len([0 : 0.001 : 1]) / 100);", 0, 0, 0), -10.01));
    CHECK(close(dist_of("sphere(len([0.1 : 0.1 : 1]));", 0, 0, 0), -10));
    CHECK(close(dist_of("sphere(len([0 : 1 : 99.5]));", 0, 0, 0), -100));  // (not 101: 100 is past the end)
    CHECK(close(dist_of("for (x = [0 : 0.1 : 10]) translate([x, 0, 0]) sphere(0.02);", 10, 0, 0), -0.02));
}

TEST_CASE("an if or a for that adds nothing is still one operand of a difference or intersection") {
    // As in OpenSCAD: the statement is the first operand, empty; the sphere is not promoted.
    CHECK(dist_of("let n = 0;\ndifference { for (i = [1 : n]) translate([i, 0, 0]) box(1); sphere(1); }", 0, 0, 0) > 1e19f);
    CHECK(dist_of("difference { if (false) box(1); sphere(1); }", 0, 0, 0) > 1e19f);
    CHECK(dist_of("intersection { if (false) box(1); sphere(1); sphere(2); }", 0, 0, 0) > 1e19f);
    CHECK(dist_of("def holes(n) = { for (i = [1 : n]) box(1); };\ndifference { holes(0); sphere(1); }", 0, 0, 0) > 1e19f);
    CHECK(dist_of("intersection { for (i = [1 : 0]) box(1); }", 0, 0, 0) > 1e19f);
    // A setting under an if adds no operand; in a union an empty operand changes nothing.
    CHECK(close(dist_of("difference { if (false) camera(position = [0, 0, 5]); sphere(1); box(0.5); }", 0, 0, 0), 0.25));
    CHECK(close(dist_of("union { for (i = [1 : 0]) sphere(1); translate([5, 0, 0]) sphere(1); }", 0, 0, 0), 4));
    CHECK(close(dist_of("difference { if (true) sphere(1); translate([1, 0, 0]) sphere(0.5); }", -0.5, 0, 0), -0.5));
}

TEST_CASE("an index that varies picks from a list of numbers or of vectors, rounded and clamped") {
    const char* f = "field (p) -> length(p) - [0.5, 1, 1.5, 1, 0.5][p.x];";
    CHECK(close(dist_of(f, 0.6f, 0, 0), -0.4));  // index 1
    CHECK(close(dist_of(f, 2.4f, 0, 0), 0.9));   // index 2
    CHECK(close(dist_of(f, -3, 0, 0), 2.5));     // clamped to the first
    CHECK(close(dist_of(f, 9, 0, 0), 8.5));      // ... and the last
    CHECK(close(dist_of("let c = [[0, 0, 0], [0, 1, 0], [0, 2, 0], [0, 3, 0], [0, 4, 0]];\n"
                        "field (p) -> length(p - c[p.y]) - 0.5;", 0.2f, 3, 0), -0.3));
    CHECK(test::first_error_line("let l = [1, [2, 3], 4, 5, 6];\nfield (p) -> length(p) - l[p.x];") ==
          "test.sdf:2:28: error: an index must be known when the script runs (it depends on the point, on time or on a param)");
}

TEST_CASE("len counts a list's, a vector's, a range's elements and a string's characters") {
    CHECK(close(dist_of("let pts = [[0, 0], [1, 0], [0.5, 1], [0, 2]]; sphere(len(pts));", 0, 0, 0), -4));
    CHECK(close(dist_of("sphere(len([1, 2, 3]));", 0, 0, 0), -3));
    CHECK(close(dist_of("sphere(len([0 : 2 : 9]));", 0, 0, 0), -5));  // 0, 2, 4, 6, 8
    CHECK(close(dist_of("sphere(len(\"h\u00e9llo\"));", 0, 0, 0), -5));
    CHECK(close(dist_of("let p = [[0, 0], [2, 0], [1, 2]]; for (i = [0 : len(p) - 1]) translate([p[i][0], p[i][1], 0]) sphere(0.5);",
                        1, 2, 0), -0.5));
}

TEST_CASE("concat, lookup and norm, as OpenSCAD's") {
    CHECK(close(dist_of("let a = concat([1, 2], [3], 4); sphere(len(a) + a[3]);", 0, 0, 0), -8));
    CHECK(close(dist_of("let v = concat([1], 2); translate(concat(v, 0)) sphere(0.5);", 1, 2, 0), -0.5));  // 3 numbers: a vector
    CHECK(close(dist_of("let pts = concat([[0, 0]], [[2, 0], [1, 2]]); sphere(len(pts));", 0, 0, 0), -3));
    const char* table = "let t = [[0, 1], [2, 5], [1, 3]];\n";  // (any order)
    CHECK(close(dist_of(std::string(table) + "sphere(lookup(1.5, t));", 0, 0, 0), -4));
    CHECK(close(dist_of(std::string(table) + "sphere(lookup(-3, t));", 0, 0, 0), -1));
    CHECK(close(dist_of(std::string(table) + "sphere(lookup(9, t));", 0, 0, 0), -5));
    // A key that varies with the point: the radius grows with y.
    const std::string f = "field (p) -> length(p) - lookup(p.y, [[-1, 0.5], [1, 1.5]]);";
    CHECK(close(dist_of(f, 0, 0, 0), -1));
    CHECK(close(dist_of(f, 0, 0.5, 0), -0.75));
    CHECK(close(dist_of("sphere(norm([0, 3, 4]));", 0, 0, 0), -5));
    CHECK(close(dist_of("sphere(max([1]) + min([5, 4, 3, 2, 0.5]));", 0, 0, 0), -1.5));  // max of a list, as OpenSCAD's
    CHECK(test::first_error_line("sphere(max([]));") == "test.sdf:1:12: error: max of an empty list");
    CHECK(test::first_error_line("sphere(lookup(1, 2));") == "test.sdf:1:18: error: lookup's table is a list of [key, value] pairs, not a number");
    CHECK(test::first_error_line("sphere(lookup(1, []));") == "test.sdf:1:18: error: lookup's table is empty");
    CHECK(test::first_error_line("sphere(lookup(0.5, [[0, [0, 0]], [1, [1, 1]]]));") ==
          "test.sdf:1:20: error: lookup's table holds [key, value] pairs of numbers; this pair holds a 2-component vector");
}

TEST_CASE("OpenSCAD's [x, y] moves, mirrors and scales, and a zero mirror normal that mirrors nothing") {
    // Hole positions as 2D points: z is 0 (a scale's is 1).
    const char* holes = "let holes = [[3, 0], [-3, 0]];\nextrude(1) difference { square(10); for (p = holes) translate(p) circle(1); }";
    CHECK(close(dist_of(holes, 3, 0, 0), 1));
    CHECK(close(dist_of(holes, -3, 0, 0), 1));
    CHECK(close(dist_of("scale([2, 1]) sphere(1);", 0, 0, 1), 0));
    CHECK(close(dist_of("mirror([1, 0]) translate([3, 0, 0]) sphere(1);", -3, 0, 0), -1));
    // for (m = [0, 1]) mirror([m, 0, 0]): both copies.
    const char* both = "for (m = [0, 1]) mirror([m, 0, 0]) translate([3, 0, 0]) sphere(1);";
    CHECK(close(dist_of(both, 3, 0, 0), -1));
    CHECK(close(dist_of(both, -3, 0, 0), -1));
    CHECK(test::first_error_line("translate([1, 2]) rotate([1, 2]) sphere(1);") == "test.sdf:1:26: error: rotate([x, y, z]) takes a 3-component vector of angles");
    CHECK(test::first_error_line("extrude(height = 2) circle(1);") ==
          "test.sdf:1:9: error: extrude has no parameter 'height': the height is h, extrude(h = 2) (OpenSCAD's linear_extrude(height = 2))");
}

TEST_CASE("a script's own len, norm, concat, lookup or param (names the contract does not reserve) wins") {
    CHECK(close(dist_of("let len = 3; sphere(len);", 0, 0, 0), -3));
    CHECK(close(dist_of("def norm(v) = abs(v[0]) + abs(v[1]); sphere(norm([3, 4]));", 0, 0, 0), -7));
    CHECK(close(dist_of("def concat(a, b) = a + b; sphere(concat(1, 2));", 0, 0, 0), -3));
    CHECK(test::first_error_line("let sin = 2; sphere(sin);") == "test.sdf:1:5: error: 'sin' is a built-in name and cannot be redefined");
}

TEST_CASE("atan takes one argument or two (GLSL's atan(y, x)), and says so") {
    CHECK(close(dist_of("sphere(atan(1, 1) * 4);", 0, 0, 0), -3.14159265f));
    CHECK(test::first_error_line("sphere(atan(1, 2, 3));") == "test.sdf:1:8: error: atan takes 1 to 2 arguments, not 3");
    CHECK(test::first_error_line("sphere(atan());") == "test.sdf:1:8: error: atan takes 1 to 2 arguments, not 0");
}

TEST_CASE("if/else at statement level and ?: in expressions") {
    CHECK(close(dist_of("let r = 0.5; if (r > 0.3) sphere(r); else box(r);", 0, 0, 1), 0.5));
    CHECK(close(dist_of("let r = 0.2; if (r > 0.3) sphere(r); else box(r);", 0, 0, 1), 0.9));
    CHECK(close(dist_of("let k = 1; k > 0 ? sphere(1) : { box(1); };", 2, 0, 0), 1));
    CHECK(close(dist_of("let k = -1; k > 0 ? sphere(1) : { box(1); translate([5, 0, 0]) box(1); };", 5, 0, 0), -0.5));
    CHECK(close(dist_of("sphere(true && !false ? 1 : 2);", 0, 0, 0), -1));
}

TEST_CASE("vectors broadcast like GLSL, swizzles and indexing") {
    CHECK(close(dist_of("translate([1, 2, 3] * 2 - 1) sphere(1);", 1, 3, 5), -1));
    CHECK(close(dist_of("let v = [1, 2, 3]; translate(v.zyx) sphere(0.5);", 3, 2, 1), -0.5));
    CHECK(close(dist_of("let v = [1, 2, 3]; sphere(v[2] + v.x);", 0, 0, 0), -4));
    CHECK(close(dist_of("let c = [0.1, 0.2, 0.3]; sphere(c.b * 10 + c.r);", 0, 0, 0), -3.1));
    CHECK(close(dist_of("sphere(length([3, 4]) + dot([1, 2, 3], [1, 1, 1]));", 0, 0, 0), -11));
    CHECK(close(dist_of("translate(cross([1, 0, 0], [0, 1, 0]) * 4) sphere(1);", 0, 0, 4), -1));
    CHECK(close(dist_of("sphere(mod(-1, 3) + 7 % 4);", 0, 0, 0), -5));
}

TEST_CASE("built-in math and constants") {
    CHECK(close(dist_of("sphere(sin(pi / 2) + cos(0) + sqrt(4) + pow(2, 3) + abs(-1));", 0, 0, 0), -13));
    CHECK(close(dist_of("sphere(clamp(5, 0, 2) + mix(0, 10, 0.25) + step(0.5, 0.7) + smoothstep(0, 1, 0.5));", 0, 0, 0), -6));
    CHECK(close(dist_of("sphere(degrees(radians(90)) / 90 + floor(1.7) + ceil(1.2) + fract(2.25) + sign(-3) + 2);", 0, 0, 0), -5.25));
    CHECK(close(dist_of("sphere(atan2(1, 1) * 4 / pi + atan(1, 1) * 4 / pi + tau / pi + e - e);", 0, 0, 0), -4));
    CHECK(close(dist_of("sphere(min(3, 1, 2) + max([1, 5, 2]) + length(normalize([3, 0, 4])));", 0, 0, 0), -7));
    CHECK(close(dist_of("sphere(exp(log(2)) + distance([0, 0, 0], [0, 3, 4]));", 0, 0, 0), -7));
}

TEST_CASE("a statement that is an expression of type shape adds it") {
    CHECK(close(dist_of("let c = cylinder(2, 1); c;", 0, 0, 0), -1));
    CHECK(close(dist_of("{ sphere(1); translate([4, 0, 0]) sphere(1); }", 4, 0, 0), -1));
}

TEST_CASE("recursion unrolls at compile time") {
    const char* tower =
        "def tower(n) = n == 0 ? sphere(0.5) : union { sphere(0.5); translate([0, 1, 0]) tower(n - 1); };\n"
        "tower(3);";
    CHECK(close(dist_of(tower, 0, 3, 0), -0.5));
    CHECK(close(dist_of(tower, 0, 4, 0), 0.5));
}

TEST_CASE("custom fields: var, reassignment, loops, shapes applied to points") {
    CHECK(close(dist_of("field (p) -> length(p) - 1;", 2, 0, 0), 1));
    CHECK(close(dist_of("field(bound = 2) (p) -> 2 * (length(p) - 1);", 3, 0, 0), 2));
    CHECK(close(dist_of("field (p) -> box(2)(p);", 3, 0, 0), 2));
    const char* hollow =
        "def hollow(s, w) = field (p) -> max(s(p), -(s(p) + w));\n"
        "hollow(sphere(1), 0.2);";
    CHECK(close(dist_of(hollow, 0, 0, 0), 0.8));
    CHECK(close(dist_of(hollow, 0.9, 0, 0), -0.1));
    const char* counter =
        "field (p) -> { var d = 10; var s = 1; for (i = [1 : 3]) { s = s * 2; d = min(d, length(p) - s); } d };";
    CHECK(close(dist_of(counter, 0, 0, 0), -8));
}

TEST_CASE("the menger sponge of LANGUAGE.md section 7") {
    const char* menger = R"(
def menger(n) = field (p) -> {
    var d = box(2)(p);
    var s = 1;
    for (m = [1 : n]) {
        let a = mod(p * s, 2) - 1;
        s = s * 3;
        let r = abs(1 - 3 * abs(a));
        let c = (min(max(r.x, r.y), min(max(r.y, r.z), max(r.z, r.x))) - 1) / s;
        d = max(d, c);
    }
    d
};
menger(4);
)";
    auto c = test::compile_text(menger);
    // The centre hole goes through along every axis; the corner cube is solid.
    CHECK(test::dist(c->cs, 0, 0, 0) > 0);
    CHECK(test::dist(c->cs, 0.99f, 0.99f, 0.99f) < 0);
    CHECK(test::dist(c->cs, 0.9f, 0.9f, 0.9f) > 0);  // inside a level-3 hole
    CHECK(close(test::dist(c->cs, 3, 0.9, 0.9), 2));
}

TEST_CASE("time is 0 by default and folds to the frame's value") {
    CHECK(close(dist_of("sphere(1 + time);", 0, 0, 0), -1));
    InterpretOptions o;
    o.time = 2.0f;
    auto c = test::compile_text("translate([time, 0, 0]) sphere(1);", "t.sdf", o);
    CHECK(close(test::dist(c->cs, 2, 0, 0), -1));
}

TEST_CASE("scene settings are read") {
    auto c = test::compile_text(
        "camera(position = [0, 3, 9], target = [0, 1, 0], fov = 40);\n"
        "light(position = [5, 8, 4], color = [1, 0.9, 0.8], intensity = 60);\n"
        "light(direction = [0, -1, 0]);\n"
        "ambient([0.1, 0.2, 0.3]); background(0.5);\n"
        "render(width = 320, height = 200, samples = 2, max_steps = 99, max_distance = 50, epsilon = 1e-3, shadows = false, ao = false, max_bounces = 1);\n"
        "sphere(1);");
    const CompiledScene& s = c->cs;
    CHECK(s.camera.position == glm::vec3(0, 3, 9));
    CHECK(s.camera.target == glm::vec3(0, 1, 0));
    CHECK(s.camera.fov == 40);
    REQUIRE(s.lights.size() == 2);
    CHECK(s.lights[0].intensity == 60);
    CHECK(!s.lights[0].directional);
    CHECK(s.lights[1].directional);
    CHECK(s.lights[1].direction == glm::vec3(0, -1, 0));
    CHECK(s.ambient == glm::vec3(0.1f, 0.2f, 0.3f));
    CHECK(s.background == glm::vec3(0.5f));
    CHECK(s.render.width == 320);
    CHECK(s.render.height == 200);
    CHECK(s.render.samples == 2);
    CHECK(s.render.max_steps == 99);
    CHECK(s.render.max_distance == 50);
    CHECK(s.render.epsilon == Approx(1e-3));
    CHECK(!s.render.shadows);
    CHECK(!s.render.ao);
    CHECK(s.render.max_bounces == 1);
}

TEST_CASE("without camera(), a scene around the default camera or out of its view is framed") {
    // A model in millimetres (as OpenSCAD's): the default camera at [0, 0, 5] is inside it.
    auto compiled = test::compile_text("translate([0, 10, 0]) box(40);");
    const CompiledScene& big = compiled->cs;
    CHECK(big.camera.target.x == Approx(0.0f).margin(1e-5));
    CHECK(big.camera.target.y == Approx(10.0f));
    const float dist = glm::length(big.camera.position - big.camera.target);
    CHECK(dist == Approx(1.05f * 20.0f * std::sqrt(3.0f) / std::sin(glm::radians(22.5f))).epsilon(0.01));
    CHECK(big.camera.position.z > 20.0f);  // outside the box, in front of it
    CHECK(test::dist(big, big.camera.position.x, big.camera.position.y, big.camera.position.z) > 0.0f);
    // A plate just in front of the camera (not around it) is too.
    auto plate = test::compile_text("box([60, 40, 2]);");
    CHECK(plate->cs.camera.position.z > 50.0f);
    // A scene wholly out of the default view is framed too.
    auto behind = test::compile_text("translate([0, 0, 500]) sphere(1);");
    CHECK(behind->cs.camera.target.z == Approx(500.0f));
    CHECK(glm::length(behind->cs.camera.position - glm::vec3(0, 0, 500)) < 10.0f);
    // Not in a script that reads time (an animation's camera would follow its bounds).
    CHECK(test::compile_text("translate([0, 0, time]) box(40);")->cs.camera.position == glm::vec3(0, 0, 5));
    // Elsewhere, and with a camera(), the camera stays where it was put.
    CHECK(test::compile_text("sphere(1);")->cs.camera.position == glm::vec3(0, 0, 5));
    CHECK(test::compile_text("camera(position = [0, 0, 5]); box(40);")->cs.camera.position == glm::vec3(0, 0, 5));
}

TEST_CASE("materials are values and modifiers, the inner one wins") {
    auto c = test::compile_text(
        "let gold = material(color = [0.9, 0.7, 0.2], specular = 0.6, shininess = 64);\n"
        "material(color = [1, 0, 0]) { material(gold) sphere(1); translate([3, 0, 0]) sphere(1); }\n"
        "translate([-3, 0, 0]) color([0, 0, 1]) sphere(1);");
    auto mat_at = [&](float x) { return eval_scalar(c->cs.shading, x, 0, 0); };
    auto g = mat_at(0);
    CHECK(g[1] == Approx(0.9));
    CHECK(g[2] == Approx(0.7));
    CHECK(g[3] == Approx(0.2));
    CHECK(g[5] == Approx(64));
    auto r = mat_at(3);
    CHECK(r[1] == Approx(1));
    CHECK(r[2] == Approx(0));
    auto b = mat_at(-3);
    CHECK(b[3] == Approx(1));
    CHECK(b[1] == Approx(0));
    // color's parameter is named like material's.
    auto named = test::compile_text("color(color = [0, 1, 0]) sphere(1);");
    auto gr = eval_scalar(named->cs.shading, 0, 0, 0);
    CHECK(gr[2] == Approx(1));
    CHECK(gr[1] == Approx(0));
}

TEST_CASE("materials blend across smooth operations") {
    auto c = test::compile_text(
        "smooth_union(1) { material(color = [1, 0, 0]) sphere(1); material(color = [0, 0, 1]) translate([1.5, 0, 0]) sphere(1); }");
    auto mid = eval_scalar(c->cs.shading, 0.75f, 0, 0);  // equidistant: an even blend
    CHECK(mid[1] == Approx(0.5).margin(1e-5));
    CHECK(mid[3] == Approx(0.5).margin(1e-5));
    auto left = eval_scalar(c->cs.shading, -0.9f, 0, 0);  // far from the blend: pure red
    CHECK(left[1] == Approx(1));
    CHECK(left[3] == Approx(0));
}
