// The parser's errors: syntax errors (exact text and position), the formatted diagnostic,
// and the nesting limit, which the limit decides, not the build or the caller's stack.
#include <catch2/catch.hpp>

#include <string>

#include <pthread.h>

#include <fmt/format.h>

#include "lang/ast.hpp"
#include "parser_support.hpp"

using namespace sdfc;
using namespace sdfc::ast;
using namespace sdfc::test;

// ------------------------------------------------------------------------- errors

TEST_CASE("syntax errors: text and position", "[parser]") {
    CHECK(error_of("sphere(1;") == "1:9: expected ')'");
    CHECK(error_of("x = (1 + 2;") == "1:11: expected ')'");
    CHECK(error_of("let a = 1\nlet b = 2;") == "1:10: expected ';' after the statement");
    CHECK(error_of("sphere(1) // a comment\n\n") == "1:10: expected ';' after the statement");
    CHECK(error_of("box(1) /* a\n comment */") == "1:7: expected ';' after the statement");
    CHECK(error_of("x = \"s\" y = 2;") == "1:8: expected ';' after the statement");
    CHECK(error_of("a;\n  /* never closed\n") == "2:3: unterminated comment");
    CHECK(error_of("import \"lib/a.sdf;\n") == "1:8: unterminated string");
    CHECK(error_of("x = \"abc") == "1:5: unterminated string");
    CHECK(error_of("x = \"a\\qb\";") == "1:7: unknown escape sequence in a string (use \\\", \\\\, \\n or \\t)");
    CHECK(error_of("sphere(1) @ box(2);") == "1:11: unexpected character '@'");
    CHECK(error_of("x = 1 # 2;") == "1:7: unexpected character '#'");
    CHECK(error_of("x = a & b;") == "1:7: unexpected character '&' (did you mean '&&'?)");
    CHECK(error_of("x = é;") == "1:5: unexpected character 'é'");
    CHECK(error_of(std::string("x = 1;\n\0", 8)) == "2:1: unexpected character U+0000");
    CHECK(error_of("x = 1;\x01") == "1:7: unexpected character U+0001");
    CHECK(error_of("x = 1 +;") == "1:8: expected an expression after the operator");
    CHECK(error_of("x = a ||\n;") == "2:1: expected an expression after '||'");
    CHECK(error_of("x = -;") == "1:6: expected an expression after '-'");
    CHECK(error_of("x = ();") == "1:6: expected an expression");
    CHECK(error_of("x = a ? b;") == "1:10: expected ':' in the conditional expression (cond ? a : b)");
    CHECK(error_of("f(1 2);") == "1:5: expected ')'");
    CHECK(error_of("x = [1, 2 3];") == "1:11: expected ',' or ']'");
    CHECK(error_of("x = [0 : 1 : 2 : 3];") == "1:16: expected ']' to close the range");
    CHECK(error_of("x = v[1;") == "1:8: expected ']'");
    CHECK(error_of("x = v.;") == "1:7: expected swizzle letters (such as .xyz) after '.'");
    CHECK(error_of("x = field (p) p;") == "1:15: expected '->' after the field's parameter");
    CHECK(error_of("x = field p -> p;") == "1:11: expected '(' and the field's parameter name, as in field (p) -> ...");
    CHECK(error_of("x = field (p) ->;") == "1:17: expected an expression after '->'");
    CHECK(error_of("union { a; ") == "1:12: expected '}'");
    CHECK(error_of("union { a; )") == "1:12: expected '}'");
    CHECK(error_of("a; }") == "1:4: unmatched '}'");
    CHECK(error_of(")") == "1:1: expected a statement");
    CHECK(error_of("if (a) else b;") == "1:8: expected a statement");
    CHECK(error_of("if a) b;") == "1:4: expected '(' after 'if'");
    CHECK(error_of("if () b;") == "1:5: expected a condition");
    CHECK(error_of("if (a b;") == "1:8: expected ')' after the condition");
    CHECK(error_of("for i = [0:1]) b;") == "1:5: expected '(' after 'for'");
    CHECK(error_of("for (1) b;") == "1:6: expected a loop variable name");
    CHECK(error_of("for (i [0:1]) b;") == "1:8: expected '=' after the name");
    CHECK(error_of("for (i = ) b;") == "1:10: expected a range or a vector to iterate over");
    CHECK(error_of("for (i = v; b;") == "1:11: expected ')' after the loop variables");
    CHECK(error_of("let = 1;") == "1:5: expected a name after 'let'");
    CHECK(error_of("var 1 = 1;") == "1:5: expected a name after 'var'");
    CHECK(error_of("let a 1;") == "1:7: expected '=' after the name");
    CHECK(error_of("let a = ;") == "1:9: expected an expression after '='");
    CHECK(error_of("def (x) = 1;") == "1:5: expected a name after 'def'");
    CHECK(error_of("def f = 1;") == "1:7: expected '(' after the function name");
    CHECK(error_of("def f(a, 1) = 1;") == "1:10: expected a parameter name");
    CHECK(error_of("def f(1) = 1;") == "1:7: expected a parameter name");
    CHECK(error_of("def f(a, if) = 1;") == "1:10: expected a parameter name ('if' is a keyword)");
    CHECK(error_of("let a for") == "1:7: expected '=' after the name");
    CHECK(error_of("x = 'a';") == "1:5: unexpected character \"'\" (strings are written in double quotes)");
    CHECK(error_of("def f(a b) = 1;") == "1:9: expected ')' after the parameters");
    CHECK(error_of("def f(a) a;") == "1:10: expected '=' or '{' after the parameters");
    CHECK(error_of("def f(a) = a") == "1:13: expected ';' after the statement");
    CHECK(error_of("import lib;") == "1:8: expected a path string after 'import'");
    CHECK(error_of("f(x = );") == "1:7: expected an expression after '='");
    // Errors on later lines, after multi-byte characters (columns count bytes).
    CHECK(error_of("// ñ\nlet é = 1;") == "2:5: unexpected character 'é'");
    CHECK(error_of("x = \"ñ\" +;") == "1:11: expected an expression after the operator");
}

TEST_CASE("the formatted diagnostic quotes the line with a caret", "[parser]") {
    SourceFile f("scene.sdf", "sphere(1);\ntranslate([1, 0, 0] box(1);\n");
    try {
        parse(f);
        FAIL("no error");
    } catch (const CompileError& e) {
        CHECK(e.formatted() ==
              "scene.sdf:2:21: error: expected ')'\n"
              "translate([1, 0, 0] box(1);\n"
              "                    ^\n");
    }
}

// ---------------------------------------------------------------------- nesting limit

TEST_CASE("deep nesting is an error, not a crash", "[parser]") {
    const int n = 100000;
    auto message = [](const std::string& text) {
        SourceFile f("deep.sdf", text);
        try {
            parse(f);
        } catch (const CompileError& e) {
            return e.diagnostics().at(0).message;
        }
        return std::string("no error");
    };
    const std::string limit = "nesting deeper than 256 levels (raise it with --max-nesting)";
    CHECK(message(std::string(n, '(') + "1" + std::string(n, ')') + ";") == limit);
    CHECK(message(std::string(n, '{') + std::string(n, '}')) == limit);
    CHECK(message(std::string(n, '{')) == limit);
    CHECK(message("x = " + std::string(n, '[') + "1" + std::string(n, ']') + ";") == limit);
    CHECK(message("x = " + std::string(n, '-') + "1;") == limit);
    CHECK(message("x = " + std::string(n, '!') + "1;") == limit);
    std::string s;
    for (int i = 0; i < n; ++i) s += "f(";
    CHECK(message(s) == limit);
    s.clear();
    for (int i = 0; i < n; ++i) s += "a ";
    CHECK(message(s + "b;") == limit);
    s.clear();
    for (int i = 0; i < n; ++i) s += "if (c) ";
    CHECK(message(s + "a;") == limit);
    s.clear();
    for (int i = 0; i < n; ++i) s += "a ? b : ";
    CHECK(message("x = " + s + "c;") == limit);
    s.clear();
    for (int i = 0; i < n; ++i) s += "field (p) -> ";
    CHECK(message("x = " + s + "1;") == limit);
    // Long flat chains build tall trees: bounded too.
    s = "x = 1";
    for (int i = 0; i < n; ++i) s += " + 1";
    CHECK_THAT(message(s + ";"), Catch::Matchers::StartsWith("expression nested deeper than"));
    s = "x = f";
    for (int i = 0; i < n; ++i) s += "(1)";
    CHECK_THAT(message(s + ";"), Catch::Matchers::StartsWith("expression nested deeper than"));
    s = "x = v";
    for (int i = 0; i < n; ++i) s += ".x";
    CHECK_THAT(message(s + ";"), Catch::Matchers::StartsWith("expression nested deeper than"));
}

TEST_CASE("the nesting limit is a parameter", "[parser]") {
    ParseOptions opts;
    opts.max_nesting = 10;
    // A top-level statement is no level; a call's parentheses are one, as is a value's
    // expression, each parenthesis in it another.
    CHECK(error_of("x = ((((((((((1))))))))));", opts) == "1:15: nesting deeper than 10 levels (raise it with --max-nesting)");
    CHECK_NOTHROW(parse_text("x = (((((((((1)))))))));", opts));
    CHECK_NOTHROW(parse_text("sphere((((((((((1))))))))));", opts));  // 10 parentheses
    CHECK(error_of("sphere(((((((((((1)))))))))));", opts) == "1:18: nesting deeper than 10 levels (raise it with --max-nesting)");
    opts.max_nesting = 3;
    CHECK_NOTHROW(parse_text("translate(v) { sphere(1); }", opts));  // a modifier and its block count 2
    CHECK(error_of("translate(v) { sphere((1)); }", opts) == "1:24: nesting deeper than 3 levels (raise it with --max-nesting)");
    opts.max_nesting = 1;
    CHECK_NOTHROW(parse_text("sphere(1);", opts));
    // The default allows realistic depth.
    std::string s = "x = " + std::string(200, '(') + "1" + std::string(200, ')') + ";";
    CHECK_NOTHROW(parse_text(s));
    s = "union { difference { translate(v) rotate(a) scale(2) { smooth_union(0.1) { a; b; } } } }";
    CHECK_NOTHROW(parse_text(s));
    s.clear();
    for (int i = 0; i < 200; ++i) s += "{";
    for (int i = 0; i < 200; ++i) s += "}";
    CHECK_NOTHROW(parse_text(s));
    s = "x = 0";
    for (int i = 0; i < 500; ++i) s += " + 1";
    CHECK_NOTHROW(parse_text(s + ";"));
}

TEST_CASE("a flat operator chain is bounded by 4 x the nesting limit, and says how to raise it", "[parser]") {
    std::string s = "x = 1";
    for (int i = 0; i < 4100; ++i) s += "+1";
    ParseOptions opts;
    opts.max_nesting = 1024;  // sdfc's default
    CHECK(error_of(s + ";", opts) ==
          "1:5: expression nested deeper than 4096 levels: each operator of a chain is a level (split the chain "
          "with `let`, or raise the limit, 4 x --max-nesting)");
    opts.max_nesting = 2000;
    CHECK_NOTHROW(parse_text(s + ";", opts));
}

// Runs f() on a new thread with a stack of `bytes` (the caller's stack must not matter).
template <typename F>
void on_small_stack(size_t bytes, F f) {
    pthread_attr_t attr;
    REQUIRE(pthread_attr_init(&attr) == 0);
    REQUIRE(pthread_attr_setstacksize(&attr, bytes) == 0);
    pthread_t t;
    auto run = [](void* p) -> void* {
        (*static_cast<F*>(p))();
        return nullptr;
    };
    REQUIRE(pthread_create(&t, &attr, run, &f) == 0);
    pthread_attr_destroy(&attr);
    pthread_join(t, nullptr);
}

TEST_CASE("the nesting limit, not the caller's stack, decides where deep input stops", "[parser]") {
    ParseOptions opts;
    opts.max_nesting = 1024;
    const std::string ok = "x = " + std::string(1000, '(') + "1" + std::string(1000, ')') + ";";
    const std::string deep = "x = " + std::string(100000, '[') + "1" + std::string(100000, ']') + ";";
    // A 256 KB stack is used up at once (the guard keeps 512 KB); the parser moves to a
    // thread with a stack for 1024 levels.
    std::string ok_error, deep_error;
    on_small_stack(256u << 10, [&] {
        ok_error = error_of(ok, opts);
        deep_error = error_of(deep, opts);
    });
    CHECK(ok_error == "no error");
    CHECK(deep_error == "1:1029: nesting deeper than 1024 levels (raise it with --max-nesting)");
    // And on this thread, deeper than its stack allows (the main thread's 8 MB holds about
    // 1,000 levels in sanitizer builds).
    opts.max_nesting = 3000;
    CHECK(error_of("x = " + std::string(2990, '(') + "1" + std::string(2990, ')') + ";", opts) == "no error");
    CHECK(error_of(deep, opts) == "1:3005: nesting deeper than 3000 levels (raise it with --max-nesting)");
}
