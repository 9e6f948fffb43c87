// Errors a script can cause: exact texts, locations and carets (LANGUAGE.md section 9).
#include <catch2/catch.hpp>

#include "support.hpp"

using namespace sdfc;
using test::error_of;
using test::first_error_line;

TEST_CASE("a diagnostic quotes the line with a caret under the column") {
    CHECK(error_of("sphere(-1);") ==
          "test.sdf:1:8: error: argument 'r' of sphere must be zero or positive, not -1\n"
          "sphere(-1);\n"
          "       ^\n");
}

TEST_CASE("unknown names suggest the nearest known one") {
    CHECK(first_error_line("spher(1);") == "test.sdf:1:1: error: unknown name 'spher' (did you mean `sphere`?)");
    CHECK(first_error_line("let radius = 1;\nsphere(radiu);") ==
          "test.sdf:2:8: error: unknown name 'radiu' (did you mean `radius`?)");
    CHECK(first_error_line("zzzzqqq(1);") == "test.sdf:1:1: error: unknown name 'zzzzqqq'");
    // Two letters swapped count as one edit; a letter of the wrong case as half of one.
    CHECK(first_error_line("field (p) -> lenght(p) - 1;") ==
          "test.sdf:1:14: error: unknown name 'lenght' (did you mean `length`?)");
    CHECK(first_error_line("sphere(clmap(1, 0, 2));") == "test.sdf:1:8: error: unknown name 'clmap' (did you mean `clamp`?)");
    CHECK(first_error_line("sphere(PI);") == "test.sdf:1:8: error: unknown name 'PI' (did you mean `pi`?)");
    CHECK(first_error_line("render(widht = 10);\nsphere(1);") ==
          "test.sdf:1:8: error: render has no parameter 'widht' (did you mean `width`?)");
}

TEST_CASE("columns count characters, the caret counts wide ones twice, and an error at the end of the file points after the last token") {
    CHECK(error_of("let s = \"\u00fc\u00fc\u00fc\"; sphere(q);") ==
          "test.sdf:1:23: error: unknown name 'q'\n"
          "let s = \"\u00fc\u00fc\u00fc\"; sphere(q);\n"
          "                      ^\n");
    // The caret under the column as a terminal shows it: wide characters (CJK, emoji) take two.
    CHECK(error_of("let s = \"\u65e5\u672c\"; sphere(q);") ==
          "test.sdf:1:22: error: unknown name 'q'\n"
          "let s = \"\u65e5\u672c\"; sphere(q);\n"
          "                       ^\n");
    CHECK(error_of("let s = \"\U0001F389\"; sphere(q);") ==
          "test.sdf:1:21: error: unknown name 'q'\n"
          "let s = \"\U0001F389\"; sphere(q);\n"
          "                     ^\n");
    CHECK(error_of("sphere(1);\nbox(\n") ==
          "test.sdf:2:5: error: expected ')'\n"
          "box(\n"
          "    ^\n");
    CHECK(first_error_line("union {\n  sphere(1);\n\n\n") == "test.sdf:2:13: error: expected '}'");
}

TEST_CASE("a def names each parameter once") {
    CHECK(first_error_line("def f(a, a) = sphere(a);\nf(1, 2);") == "test.sdf:1:10: error: parameter 'a' is named twice in 'f'");
}

TEST_CASE("wrong argument count, unknown names and types name the parameter") {
    CHECK(first_error_line("sphere(1, 2);") ==
          "test.sdf:1:11: error: sphere takes at most 1 argument (r), but more were given");
    CHECK(first_error_line("torus(majr = 1, minor = 0.2);") ==
          "test.sdf:1:7: error: torus has no parameter 'majr' (did you mean `major`?)");
    CHECK(first_error_line("box([1, 2]);") ==
          "test.sdf:1:5: error: argument 'size' of box must be a number or a 3-component vector, not a 2-component vector");
    CHECK(first_error_line("sphere();") == "test.sdf:1:1: error: missing argument 'r' of sphere");
    CHECK(first_error_line("torus(1, major = 2);") == "test.sdf:1:10: error: argument 'major' of torus is given twice");
    CHECK(first_error_line("def f(a) = sphere(a);\nf(1, 2);") == "test.sdf:2:6: error: f takes 1 argument, but more were given");
    CHECK(first_error_line("def f(a) = sphere(a);\nf(b = 2);") == "test.sdf:2:3: error: f has no parameter 'b'");
    CHECK(first_error_line("translate(1) sphere(1);") ==
          "test.sdf:1:11: error: argument 'v' of translate must be a 3-component vector, not a number");
}

TEST_CASE("type errors and vector sizes") {
    CHECK(first_error_line("sphere([1, 2] + [1, 2, 3]);") == "test.sdf:1:15: error: vector sizes differ: 2 and 3 components");
    CHECK(first_error_line("sphere(1 + \"a\");") == "test.sdf:1:10: error: cannot apply '+' to a number and a string");
    CHECK(first_error_line("1 + 2;") ==
          "test.sdf:1:3: error: this statement computes a number but does nothing with it (a statement must be a shape or a setting)");
    CHECK(first_error_line("translate([1, 0, 0]);") ==
          "test.sdf:1:1: error: 'translate' needs a shape to apply to, e.g. translate(...) sphere(1);");
}

TEST_CASE("settings may appear once") {
    CHECK(first_error_line("camera();\ncamera();") == "test.sdf:2:1: error: a second camera statement (the first is at line 1)");
    CHECK(first_error_line("render();\nrender(width = 10);") == "test.sdf:2:1: error: a second render statement (the first is at line 1)");
}

TEST_CASE("NaN, infinity and negative sizes") {
    CHECK(first_error_line("sphere(1 / 0);") == "test.sdf:1:10: error: division by zero");
    CHECK(first_error_line("box([1, -2, 1]);") ==
          "test.sdf:1:5: error: argument 'size' of box must be zero or positive, not -2");
    CHECK(first_error_line("sphere(sqrt(-1));") == "test.sdf:1:13: error: sqrt of a negative number");
    CHECK(first_error_line("sphere(pow(10, 100));") == "test.sdf:1:8: error: this expression is not a finite number (inf)");
}

TEST_CASE("recursion and loop limits give errors, not hangs") {
    CHECK(first_error_line("def f(n) = f(n + 1);\nsphere(f(0));") ==
          "test.sdf:1:12: error: recursion deeper than 64 calls in 'f' (raise it with --max-recursion)");
    CHECK(first_error_line("for (i = [0 : 200000]) sphere(1);") ==
          "test.sdf:1:10: error: this range has 200001 elements, over the loop limit of 100000 (raise it with --max-iterations)");
}

TEST_CASE("several independent errors are all reported") {
    std::string e = error_of("sphere(-1);\nbox(1);\ntorus(1);\n");
    CHECK(e.find("test.sdf:1:8: error:") != std::string::npos);
    CHECK(e.find("test.sdf:3:1: error: missing argument 'minor' of torus") != std::string::npos);
}

TEST_CASE("a let whose value failed is reported once, not again at each use") {
    CHECK(error_of("let b = sqrt(\"x\");\nsphere(b);\nbox(b);\n") ==
          "test.sdf:1:14: error: argument 1 of sqrt must be a number or a vector, not a string\n"
          "let b = sqrt(\"x\");\n"
          "             ^\n");
    // Other errors of the script are still found; an unknown name is still one.
    const std::string e = error_of("let b = sqrt(\"x\");\nsphere(b);\ntorus(1);\nsphere(c);\n");
    CHECK(e.find("test.sdf:3:1: error: missing argument 'minor' of torus") != std::string::npos);
    CHECK(e.find("test.sdf:4:8: error: unknown name 'c'") != std::string::npos);
    CHECK(e.find("'b'") == std::string::npos);
}

TEST_CASE("a def or an assignment that failed is reported once, not again as an unknown name at its uses") {
    CHECK(error_of("def f(a, a) = a;\nsphere(f(1, 2));\n") ==
          "test.sdf:1:10: error: parameter 'a' is named twice in 'f'\n"
          "def f(a, a) = a;\n"
          "         ^\n");
    const std::string e = error_of("x = 2;\nsphere(x);\n");
    CHECK(e.find("test.sdf:1:1: error: unknown variable 'x'") == 0);
    CHECK(e.find("unknown name 'x'") == std::string::npos);
}

TEST_CASE("a message that quotes a huge name keeps its start and end") {
    const std::string e = first_error_line("sphere(" + std::string(100000, 'a') + ");");
    CHECK(e.size() < 700);
    CHECK(e.rfind("test.sdf:1:8: error: unknown name 'aaaa", 0) == 0);
    CHECK(e.find(" bytes ...] ") != std::string::npos);
    CHECK(e.substr(e.size() - 5) == "aaaa'");
}

TEST_CASE("a list's size is named where it is wrong") {
    CHECK(first_error_line("polygon([[0, 0], [1, 0]]);") == "test.sdf:1:9: error: polygon takes a list of 3 or more points [x, y], not a list of 2");
}

TEST_CASE("var is for field blocks, let cannot be reassigned") {
    CHECK(first_error_line("var x = 1;") == "test.sdf:1:1: error: 'var' is only allowed inside a field block; use 'let' (outside a field block a value never changes)");
    CHECK(first_error_line("field (p) -> { let d = 1; d = 2; d };") ==
          "test.sdf:1:27: error: 'd' is a constant (declared with let at line 1); declare it with var to reassign it");
    CHECK(first_error_line("let a = 1;\nlet a = 2;") == "test.sdf:2:5: error: 'a' is already defined in this scope (at line 1)");
    // Outside a field block, var is no way out: the message says what is.
    CHECK(first_error_line("let a = 1;\na = 2;\nsphere(a);") ==
          "test.sdf:2:1: error: 'a' is a constant (declared with let at line 1): a value outside a field block never changes; give the "
          "new value a new name, or compute it in one expression (a list comprehension, a recursive def)");
    // A failed var or module leaves no follow-on errors at its uses.
    for (const char* src : {"var a = 1;\na = 2;\nsphere(a);", "module m(s = 1) { sphere(s); }\nm();", "function f(x) = x;\nsphere(f(1));"}) {
        INFO(src);
        std::string e;
        try {
            test::compile_text(src);
        } catch (const CompileError& err) {
            e = err.formatted();
        }
        CHECK(e.find("error") != std::string::npos);
        CHECK(e.find("test.sdf:2:") == std::string::npos);
    }
}

TEST_CASE("an index must be a whole number within the vector or list") {
    CHECK(first_error_line("sphere([1, 2, 3][1.5]);") == "test.sdf:1:18: error: index 1.5 is not a whole number");
    CHECK(first_error_line("sphere([1, 2, 3][3]);") == "test.sdf:1:18: error: index 3 is out of range for a 3-component vector");
}

TEST_CASE("an error inside a def names the call it came from, the innermost") {
    CHECK(first_error_line("def opRep(p, c) = mod(p + 0.5 * c, c) - 0.5 * c;\nfield (q) -> length(opRep(q, [3, 0, 3])) - 1;") ==
          "test.sdf:1:36: error: mod by zero (in opRep, called at line 2)");
    CHECK(first_error_line("def inner(r) = sphere(-r);\ndef outer(r) = inner(r);\nouter(1);") ==
          "test.sdf:1:23: error: argument 'r' of sphere must be zero or positive, not -1 (in inner, called at line 2)");
}
