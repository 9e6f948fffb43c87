// Limits and deep input through the library: every limit is a located diagnostic, deep but
// legal trees compile, and nothing (however the limits are raised) overflows the C++ stack
// or runs without bound. The same limits through the sdfc flags: tests/cli/test_limits.cpp.
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include "support.hpp"

using namespace sdfc;
using test::compile_text;

namespace {

// The first line of the diagnostics of `src` compiled with `limits`, or "" if it compiles.
std::string first_error(const std::string& src, Limits limits = {}) {
    InterpretOptions o;
    o.limits = limits;
    try {
        compile_text(src, "test.sdf", o);
    } catch (const CompileError& e) {
        std::string s = e.formatted();
        return s.substr(0, s.find('\n'));
    }
    return "";
}

std::string repeat(const std::string& s, int n) {
    std::string out;
    for (int i = 0; i < n; ++i) out += s;
    return out;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("deep but legal trees compile: 250 nested blocks each with a translate") {
    std::string src = repeat("translate([0.01, 0, 0]) {\n", 250) + "sphere(1);\n" + repeat("}\n", 250);
    auto c = compile_text(src);
    CHECK(test::dist(c->cs, 2.5f, 0, 0) == Approx(-1.0f).margin(1e-4));
    CHECK(test::dist(c->cs, 5.5f, 0, 0) == Approx(2.0f).margin(1e-4));
    // And 250 nested parentheses, brackets and unary operators.
    CHECK(first_error("sphere(" + repeat("(", 250) + "1" + repeat(")", 250) + ");") == "");
    CHECK(first_error("sphere(" + repeat("-", 250) + "1);") == "");
    CHECK(first_error("let v = " + repeat("[", 250) + "1" + repeat("]", 250) + ";") == "");
}

TEST_CASE("100,000 nested parentheses, blocks or brackets are an error, also with the limit raised") {
    const int n = 100000;
    const std::vector<std::string> inputs{
        "sphere(" + repeat("(", n) + "1" + repeat(")", n) + ");",
        repeat("{", n) + "sphere(1);" + repeat("}", n),
        repeat("translate([0, 0, 0]) {", n) + repeat("}", n),
        "let v = " + repeat("[", n) + "1" + repeat("]", n) + ";",
        "sphere(" + repeat("-", n) + "1);",
        "let f = " + repeat("field (p) -> ", n) + "1;",
    };
    for (const auto& src : inputs) {
        CHECK(contains(first_error(src), "error: nesting deeper than 1024 levels"));
        Limits raised;  // as far as the flags go
        raised.max_nesting = 10000;
        raised.max_shape_depth = 10000;
        std::string e = first_error(src, raised);
        // Whichever stops it first; the point is a diagnostic instead of a crash.
        CHECK((contains(e, "error: nested too deeply: the C++ stack is nearly exhausted") ||
               contains(e, "error: nesting deeper than 10000 levels") || contains(e, "expression nested deeper than") ||
               contains(e, "statement nested deeper than")));
    }
}

TEST_CASE("recursion: the depth limit, and raising it cannot overflow the stack") {
    CHECK(first_error("def f(n) = n > 0 ? f(n - 1) + 1 : 0;\nsphere(f(100));") ==
          "test.sdf:1:20: error: recursion deeper than 64 calls in 'f' (raise it with --max-recursion)");
    Limits l;
    l.max_recursion = 200;
    CHECK(first_error("def f(n) = n > 0 ? f(n - 1) + 1 : 0;\nsphere(f(100));", l) == "");
    l.max_recursion = 100000;
    l.max_shape_depth = 10000;
    CHECK(contains(first_error("def f(n) = n > 0 ? f(n - 1) + 1 : 0;\nsphere(f(99000));", l),
                   "error: nested too deeply: the C++ stack is nearly exhausted"));
    std::string e = first_error("def f(n) = n > 0 ? translate([0, 0, 0]) f(n - 1) : sphere(1);\nf(99000);", l);
    CHECK((contains(e, "error: nested too deeply: the C++ stack is nearly exhausted") ||
           contains(e, "error: shapes nested more than 10000 deep")));
}

TEST_CASE("exponential recursion stops at the total call limit") {
    const std::string src = "def f(n) = n > 0 ? f(n - 1) + f(n - 1) : 1;\nsphere(f(60));";
    Limits l;
    l.max_calls = 5000;
    CHECK(first_error(src, l) ==
          "test.sdf:1:31: error: the script made more than 5000 calls in all, counting field bodies and shapes "
          "applied to points (raise it with --max-calls)");
    CHECK(first_error("def f(n) = n > 0 ? f(n - 1) + f(n - 1) : 1;\nsphere(f(10) / 1024);", l) == "");
}

TEST_CASE("a shape shared by reference counts at each use") {
    // 24 doublings: 2^25 shapes for lowering to walk, from 26 shapes built.
    std::string src = "let s0 = sphere(1);\n";
    for (int k = 1; k <= 24; ++k) src += fmt::format("let s{} = union {{ s{}; translate([0, 0, 0]) s{}; }};\n", k, k - 1, k - 1);
    src += "s24;\n";
    CHECK(contains(first_error(src), "error: the scene has more than 1000000 shapes, counting a shared shape at each use "
                                     "(raise it with --max-shapes)"));
    // Fields applied to points count the shapes they lower.
    // Fields applied to points count the shapes they lower: 6 x 101 here.
    const std::string apply = "let s = union { for (i = [0 : 99]) sphere(i); };\n"
                              "field (p) -> min(s(p), min(s(p + 1), min(s(p + 2), min(s(p + 3), min(s(p + 4), s(p + 5))))));";
    Limits l;
    l.max_calls = 500;
    CHECK(contains(first_error(apply, l), "error: the script made more than 500 calls in all"));
    l.max_calls = 1000;
    CHECK(first_error(apply, l) == "");
}

TEST_CASE("loops: per loop and in all") {
    CHECK(first_error("for (i = [0 : 100000]) sphere(1);") ==
          "test.sdf:1:10: error: this range has 100001 elements, over the loop limit of 100000 (raise it with --max-iterations)");
    Limits l;
    l.max_loop_iterations = 1000;
    l.max_total_iterations = 5000;
    CHECK(first_error("field (p) -> { var d = p.x; for (i = [1 : 2000]) d = d + 0; d };", l) ==
          "test.sdf:1:38: error: this range has 2000 elements, over the loop limit of 1000 (raise it with --max-iterations)");
    CHECK(first_error("field (p) -> { var d = p.x; for (i = [1 : 100], j = [1 : 20]) d = d + 0; d };", l) ==
          "test.sdf:1:29: error: this loop runs more than 1000 iterations (raise it with --max-iterations)");
    CHECK(first_error("field (p) -> { var d = p.x; for (i = [1 : 100]) for (j = [1 : 100]) d = d + 0; d };", l) ==
          "test.sdf:1:49: error: loops ran more than 5000 iterations in all (raise it with --max-iterations)");
}

TEST_CASE("scopes of finished iterations and calls are freed, those closures need are kept") {
    // 100,000 iterations that each make scopes; the closures of f keep theirs.
    auto c = compile_text("field (p) -> { var d = p.x; for (i = [1 : 100000]) { let k = i * 0; d = d + k; } d };\n"
                          "def f(n) = field (p) -> length(p) - n;\nfor (i = [1 : 3]) translate([i * 3, 0, 0]) f(1);");
    CHECK(test::dist(c->cs, 3, 0, 0) == Approx(-1.0f));
}

TEST_CASE("lists built by a loop nest no deeper than the nesting limit") {
    CHECK(first_error("field (p) -> { var l = [1]; for (i = [0 : 1100]) l = [l]; p.x };") ==
          "test.sdf:1:54: error: lists nested deeper than 1024 levels (raise it with --max-nesting)");
    CHECK(first_error("field (p) -> { var l = [1]; for (i = [0 : 1000]) l = [l]; p.x };") == "");
}

TEST_CASE("the shape depth limit") {
    Limits l;
    l.max_shape_depth = 50;
    CHECK(first_error("def f(n) = n > 0 ? translate([0, 0.1, 0]) f(n - 1) : sphere(1);\nf(60);", l) ==
          "test.sdf:1:20: error: shapes nested more than 50 deep (raise it with --max-shape-depth)");
    // Built by a loop, without any nesting of the script or of calls: lowering it recurses
    // (and freeing it would), as deep as the flag allows. It compiles, or the stack guard
    // stops it (sanitizer builds have larger frames); never a crash.
    l.max_shape_depth = 10000;
    l.max_loop_iterations = 100000;
    std::string e = first_error("field (p) -> { var s = sphere(1); for (i = [1 : 9990]) s = translate([0, 0, 0]) s; s(p) };", l);
    CHECK((e.empty() || contains(e, "error: nested too deeply: the C++ stack is nearly exhausted")));
    CHECK(contains(first_error("field (p) -> { var s = sphere(1); for (i = [1 : 20000]) s = translate([0, 0, 0]) s; s(p) };", l),
                   "error: shapes nested more than 10000 deep (raise it with --max-shape-depth)"));
    // A list as deep as the nesting flag allows is freed without trouble.
    l.max_nesting = 10000;
    CHECK(first_error("field (p) -> { var l = [1]; for (i = [1 : 9990]) l = [l]; p.x };", l) == "");
}

TEST_CASE("the IR operation limit") {
    Limits l;
    l.max_ops = 300;
    CHECK(contains(first_error("field (p) -> { var d = p.x; for (i = [1 : 100]) d = min(d, length(p - [i, 0, 0]) - 0.5); d };", l),
                   "error: the program grew past 300 operations (raise it with --max-ops)"));
}
