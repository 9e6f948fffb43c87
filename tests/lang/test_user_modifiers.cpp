// User modifiers (issue 16, item 1): a def whose last parameter, without a default, is left
// to the shape written after the call, as OpenSCAD's modules take children().
#include <catch2/catch.hpp>

#include "support.hpp"

using namespace sdfc;
using namespace sdfc::test;

TEST_CASE("a def written before a shape or a block takes it as its last argument", "[lang]") {
    const std::string defs = "def at(i, j, s) = translate([i * 3, 0, j * 3]) s;\n"
                             "def twice(s) = union { s; translate([0, 2, 0]) s; };\n";
    // Before an operation with a block.
    CHECK(dist_of(defs + "at(2, 2) intersection { sphere(1.2); box(2); }", 6, 0, 6) == Approx(-1.0f));
    // Before a block of statements (their union).
    CHECK(dist_of(defs + "at(0, 1) { sphere(0.5); box(0.2); }", 0, 0, 3) == Approx(-0.5f));
    // Chained with other modifiers, the arguments named or not.
    const std::string chain = defs + "twice() at(1, 0) sphere(0.3);";
    CHECK(dist_of(chain, 3, 0, 0) == Approx(-0.3f));
    CHECK(dist_of(chain, 3, 2, 0) == Approx(-0.3f));
    CHECK(dist_of(defs + "at(j = 1, i = 0) sphere(1);", 0, 0, 3) == Approx(-1.0f));
    // Called with every argument, it is a plain function.
    CHECK(dist_of(defs + "at(1, 0, sphere(1));", 3, 0, 0) == Approx(-1.0f));
}

TEST_CASE("a modifier takes a conditional shape, bare or in parentheses", "[lang]") {
    // The contract's `k > 0 ? sphere(1) : { ... }` is a shape statement, so a modifier applies
    // to all of it (not to k); in parentheses it reads as a call of the operation.
    CHECK(dist_of("let k = 2;\ntranslate([4, 0, 0]) k > 1 ? sphere(0.3) : box(0.5);", 4, 0, 0) == Approx(-0.3f));
    CHECK(dist_of("let k = 0;\ntranslate([4, 0, 0]) k > 1 ? sphere(0.3) : box(0.5);", 4, 0, 0) == Approx(-0.25f));
    CHECK(dist_of("let k = 2;\ntranslate([4, 0, 0]) (k > 1 ? sphere(0.3) : box(0.5));", 4, 0, 0) == Approx(-0.3f));
    CHECK(dist_of("rotate(y = 90) translate([0, 2, 0]) 1 > 0 ? sphere(0.5) : box(1);", 0, 2, 0) == Approx(-0.5f));
    CHECK(dist_of("def at(v, s) = translate(v) s;\nlet k = 2;\nat([0, 0, 3]) k > 1 ? sphere(1) : box(1);", 0, 0, 3) ==
          Approx(-1.0f));
    CHECK(first_error_line("translate([1, 0, 0]) (1 + 2);") ==
          "test.sdf:1:23: error: the target of translate must be a shape, not a number");
}

TEST_CASE("a modifier takes an if with else written as OpenSCAD's statements (its first branch ended before else)", "[lang]") {
    CHECK(dist_of("let k = 0;\ntranslate([5, 0, 0]) if (k > 0) sphere(0.5); else box(1);", 5, 0, 0) == Approx(-0.5f));
    CHECK(dist_of("let k = 1;\ntranslate([5, 0, 0]) if (k > 0) sphere(0.5); else box(1);", 5, 0, 0) == Approx(-0.5f));
    // Chains, else if, a user modifier, a for target, inside a block.
    const std::string s = "def up(s) = translate([0, 3, 0]) s;\n"
                          "union {\n"
                          "  translate([5, 0, 0]) up() if (1 > 2) sphere(0.5); else if (2 > 3) sphere(2); else box(1);\n"
                          "  translate([0, 6, 0]) for (i = [0:1]) if (i == 0) sphere(0.25); else translate([0, 0, 3]) box(1);\n"
                          "}\n";
    CHECK(dist_of(s, 5, 3, 0) == Approx(-0.5f));
    CHECK(dist_of(s, 0, 6, 0) == Approx(-0.25f));
    CHECK(dist_of(s, 0, 6, 3) == Approx(-0.5f));
    // The else goes with the nearest if, as in OpenSCAD.
    CHECK(dist_of("if (true) translate([5, 0, 0]) if (false) sphere(0.5); else box(1);", 5, 0, 0) == Approx(-0.5f));
    CHECK(first_error_line("translate([5, 0, 0]) if (true) sphere(1); else;") == "test.sdf:1:47: error: expected an expression");
}

TEST_CASE("a user modifier's errors name it", "[lang]") {
    CHECK(first_error_line("def f(x) = x * 2;\nf(1) sphere(1);") ==
          "test.sdf:2:1: error: a number is written before a shape but is not an operation");
    CHECK(first_error_line("def g(a, s) = a + 1;\ng(1) sphere(1);") ==
          "test.sdf:2:1: error: g is written before a shape, so it must return a shape, but it returns a number");
    CHECK(first_error_line("def at(v, s) = translate(v) s;\nlet k = 3;\nat([1, 0, 0]) k;") ==
          "test.sdf:3:15: error: the target of at must be a shape, not a number");
}

TEST_CASE("list comprehensions give the iterations' values, an if without else none, a for inside runs nested", "[lang]") {
    // [0, 1, 4, 9, 16]: the sphere's radius is 16 / 16.
    CHECK(dist_of("let l = [for (i = [0 : 4]) i * i]; sphere(l[4] / 16);", 0, 0, 0) == Approx(-1.0f));
    // Three numbers make a vector, as a literal's do.
    CHECK(dist_of("translate([for (i = [0 : 2]) i]) sphere(1);", 0, 1, 2) == Approx(-1.0f));
    // A filter: [0, 2, 4], the last is 4.
    CHECK(dist_of("let l = [for (i = [0 : 5]) if (i % 2 == 0) i]; sphere(l[2]);", 0, 0, 0) == Approx(-4.0f));
    // Nested generators, as OpenSCAD's: [1, 2, 2, 4, 3, 6], then [[2, 0], [2, 1], [4, 0], [4, 1]]
    // (an if choosing a for), then [-1, 2, 3].
    CHECK(dist_of("let v = [for (i = [1 : 3]) for (j = [1 : 2]) i * j]; sphere(v[5]);", 0, 0, 0) == Approx(-6.0f));
    CHECK(dist_of("let w = [for (i = [1 : 4]) if (i % 2 == 0) for (j = [0 : 1]) [i, j]]; sphere(w[3][0] + w[3][1] + w[1][1]);", 0, 0, 0) ==
          Approx(-6.0f));
    CHECK(dist_of("let u = [for (i = [1 : 3]) if (i > 1) i else -i]; sphere(u[1] + u[2] + u[0]);", 0, 0, 0) == Approx(-4.0f));
    // An outline for polygon: a square from its corners.
    CHECK(dist_of("extrude(2) polygon([for (a = [45 : 90 : 315]) [cos(radians(a)), sin(radians(a))] * sqrt(2)]);", 0, 0, 0) ==
          Approx(-1.0f).margin(1e-5));
}
