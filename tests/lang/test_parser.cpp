// The parser: grammar sanity, the snippets of LANGUAGE.md, precedence, lexical details,
// locations, the fast paths and the dump. Syntax errors and the nesting limit are in
// test_parser_errors.cpp.
#include <catch2/catch.hpp>

#include <charconv>
#include <cstring>
#include <thread>

#include <fmt/format.h>

#include "grammar/sdf_grammar.hpp"
#include "lang/ast.hpp"
#include "parser_support.hpp"

#include <tao/pegtl/contrib/analyze.hpp>

using namespace sdfc;
using namespace sdfc::ast;
using namespace sdfc::test;

// --------------------------------------------------------------------------------- grammar

TEST_CASE("the grammar has no PEG problems (analyze)", "[parser]") {
    CHECK(tao::pegtl::analyze<sdfc::grammar::grammar>(1) == 0);
}

namespace broken {
using namespace tao::pegtl;
struct left_rec;
struct left_rec : seq<opt<one<'x'>>, left_rec, one<'y'>> {};  // may recurse without consuming
struct empty_loop : star<opt<one<'z'>>> {};                   // a loop that may not progress
}  // namespace broken

TEST_CASE("analyze detects a deliberately broken grammar", "[parser]") {
    CHECK(tao::pegtl::analyze<broken::left_rec>(-1) > 0);  // -1: quiet
    CHECK(tao::pegtl::analyze<broken::empty_loop>(-1) > 0);
}

// ------------------------------------------------------------------------ LANGUAGE.md

TEST_CASE("section 1: a first script", "[parser]") {
    Parsed p = parse_text(R"(// three-tori.sdf — a sphere "terrain", three tori, two point lights
camera(position = [0, 3, 9], target = [0, 1, 0], fov = 40);
light(position = [ 5, 8,  4], color = [1.0, 0.9, 0.8], intensity = 60);
light(position = [-6, 5, -2], color = [0.4, 0.5, 1.0], intensity = 30);
render(width = 800, height = 450, samples = 4, max_steps = 256, epsilon = 1e-4);

let gold = material(color = [0.9, 0.7, 0.2], specular = 0.6, shininess = 64);

translate([0, -100, 0]) sphere(100);                 // the terrain
for (i = [0 : 2])
    translate([(i - 1) * 2.5, 1, 0]) rotate(x = 90 + 30 * i)
        material(gold) torus(0.8, 0.25);
)");
    REQUIRE(p.size() == 7);
    CHECK(sx_stmt(&p.stmt(0)) == "(call camera position=[0 3 9] target=[0 1 0] fov=40)");
    CHECK(sx_stmt(&p.stmt(2)) == "(call light position=[(neg 6) 5 (neg 2)] color=[0.4 0.5 1] intensity=30)");
    CHECK(sx_stmt(&p.stmt(3)) ==
          "(call render width=800 height=450 samples=4 max_steps=256 epsilon=0.0001)");
    CHECK(p.stmt(4).kind == StmtKind::Let);
    CHECK(p.stmt(4).name == "gold");
    CHECK(sx_stmt(&p.stmt(5)) == "(apply (call translate [0 (neg 100) 0]) (call sphere 100))");
    const Stmt& f = p.stmt(6);
    REQUIRE(f.kind == StmtKind::For);
    REQUIRE(f.bindings.size() == 1);
    CHECK(f.bindings[0].name == "i");
    CHECK(sx(f.bindings[0].iterable.get()) == "(range 0 2)");
    CHECK(sx_stmt(f.body.get()) ==
          "(apply (call translate [(* (- i 1) 2.5) 1 0]) (apply (call rotate x=(+ 90 (* 30 i))) "
          "(apply (call material gold) (call torus 0.8 0.25))))");
    // Locations.
    CHECK(p.stmt(0).loc.line == 2);
    CHECK(p.stmt(0).loc.col == 1);
    CHECK(p.stmt(4).name_loc.line == 7);
    CHECK(p.stmt(4).name_loc.col == 5);
    CHECK(f.loc.line == 10);
    CHECK(f.body->loc.line == 11);
    CHECK(f.body->loc.col == 5);
    CHECK(f.bindings[0].loc.col == 6);
}

TEST_CASE("section 4: definitions and control", "[parser]") {
    Parsed p = parse_text(R"(let r = 0.5;                                   // constant binding (file or block scope)
def ring(R, t = 0.1) = rotate(x = 90) torus(R, t);       // function returning a shape
def lerp3(a, b, k) = a + (b - a) * k;                   // function returning a value
import "lib/furniture.sdf";                    // definitions of another file, path relative to this one
if (r > 0.3) sphere(r); else box(r);           // statement-level conditional
for (i = [0 : 7]) rotate(y = 45 * i) translate([2, 0, 0]) sphere(0.2);   // union of the iterations
for (x = [0 : 2], z = [0 : 2]) translate([x, 0, z]) box(0.4);             // nested loop
for (s = [-1, 1]) translate([s, 0, 0]) sphere(1);
let c = cylinder(2, 1); c;
def pair() = { sphere(1); box(1); };
k > 0 ? sphere(1) : { box(1); sphere(2); };
)");
    REQUIRE(p.size() == 12);
    CHECK(sx_stmt(&p.stmt(0)) == "let r = 0.5");
    CHECK(sx_stmt(&p.stmt(1)) == "def ring(R, t = 0.1) = (apply (call rotate x=90) (call torus R t))");
    CHECK(sx_stmt(&p.stmt(2)) == "def lerp3(a, b, k) = (+ a (* (- b a) k))");
    CHECK(p.stmt(3).kind == StmtKind::Import);
    CHECK(p.stmt(3).name == "lib/furniture.sdf");
    CHECK(p.stmt(3).name_loc.col == 8);
    CHECK(sx_stmt(&p.stmt(4)) == "if (> r 0.3) then (call sphere r) else (call box r)");
    CHECK(sx_stmt(&p.stmt(5)) ==
          "for (i (range 0 7)) (apply (call rotate y=(* 45 i)) (apply (call translate [2 0 0]) (call sphere 0.2)))");
    CHECK(sx_stmt(&p.stmt(6)) == "for (x (range 0 2))(z (range 0 2)) (apply (call translate [x 0 z]) (call box 0.4))");
    CHECK(sx_stmt(&p.stmt(7)) == "for (s [(neg 1) 1]) (apply (call translate [s 0 0]) (call sphere 1))");
    CHECK(sx_stmt(&p.stmt(9)) == "c");
    CHECK(sx_stmt(&p.stmt(10)) == "def pair() = {(call sphere 1); (call box 1); }");
    CHECK(sx_stmt(&p.stmt(11)) == "(? (> k 0) (call sphere 1) {(call box 1); (call sphere 2); })");
    // Def parameters and their locations.
    const Stmt& ring = p.stmt(1);
    REQUIRE(ring.params.size() == 2);
    CHECK(ring.name_loc.col == 5);
    CHECK(ring.params[1].loc.col == 13);
    CHECK(ring.params[0].default_value == nullptr);
}

TEST_CASE("section 6: operations", "[parser]") {
    CHECK(sx1("translate([1,0,0]) rotate(y = 30) box(1);") ==
          "(apply (call translate [1 0 0]) (apply (call rotate y=30) (call box 1)))");
    CHECK(sx1("union { a; b; }") == "(apply union {a; b; })");
    CHECK(sx1("difference { box(1); sphere(0.6); }") == "(apply difference {(call box 1); (call sphere 0.6); })");
    CHECK(sx1("smooth_union(0.3) { sphere(1); translate([1, 0, 0]) box(1); }") ==
          "(apply (call smooth_union 0.3) {(call sphere 1); (apply (call translate [1 0 0]) (call box 1)); })");
    CHECK(sx1("stairs_union(0.2, 4) { a; b; }") == "(apply (call stairs_union 0.2 4) {a; b; })");
    CHECK(sx1("material(color = [1, 0, 0]) sphere(1);") == "(apply (call material color=[1 0 0]) (call sphere 1))");
    CHECK(sx1("repeat([2, 0, 2], 3) round(0.1) box(1);") ==
          "(apply (call repeat [2 0 2] 3) (apply (call round 0.1) (call box 1)))");
    CHECK(sx1("rotate(angle = 45, axis = [0, 1, 0]) symmetry(x = true) sphere(1);") ==
          "(apply (call rotate angle=45 axis=[0 1 0]) (apply (call symmetry x=true) (call sphere 1)))");
    CHECK(sx1("let m = material(color = [r, g, b], specular = 0.5, shininess = 32, reflect = 0, transparency = 0, "
              "ior = 1.5, emission = [0,0,0]);")
              .rfind("let m = (call material color=[r g b]", 0) == 0);
}

TEST_CASE("section 7: custom distance fields", "[parser]") {
    Parsed p = parse_text(R"(def hollow(s, w) = field (p) -> max(s(p), -(s(p) + w));
def menger(n) = field (p) -> {
    var d = box(2)(p);
    var s = 1;
    for (m = [1 : n]) {                   // unrolled at compile time
        let a = mod(p * s, 2) - 1;
        s = s * 3;
        let r = abs(1 - 3 * abs(a));
        let c = (min(max(r.x, r.y), min(max(r.y, r.z), max(r.z, r.x))) - 1) / s;
        d = max(d, c);
    }
    d
};
menger(4);
)");
    REQUIRE(p.size() == 3);
    CHECK(sx_stmt(&p.stmt(0)) == "def hollow(s, w) = (field (p) (call max (call s p) (neg (+ (call s p) w))))");
    const Stmt& m = p.stmt(1);
    REQUIRE(m.kind == StmtKind::Def);
    const Expr& field = *m.value;
    REQUIRE(field.kind == ExprKind::Field);
    CHECK(field.text == "p");
    CHECK(field.args.empty());
    REQUIRE(field.body->kind == ExprKind::BlockExpr);
    const Block& b = *field.body->block;
    REQUIRE(b.stmts.size() == 3);
    CHECK(sx_stmt(b.stmts[0].get()) == "var d = (call (call box 2) p)");
    CHECK(b.stmts[1]->kind == StmtKind::Var);
    const Stmt& loop = *b.stmts[2];
    REQUIRE(loop.kind == StmtKind::For);
    CHECK(sx(loop.bindings[0].iterable.get()) == "(range 1 n)");
    REQUIRE(loop.body->kind == StmtKind::Expr);
    const Block& inner = *loop.body->value->block;
    REQUIRE(inner.stmts.size() == 5);
    CHECK(inner.result == nullptr);
    CHECK(sx_stmt(inner.stmts[1].get()) == "s = (* s 3)");
    CHECK(sx_stmt(inner.stmts[3].get()) ==
          "let c = (/ (- (call min (call max (.x r) (.y r)) (call min (call max (.y r) (.z r)) (call max (.z r) (.x r)))) 1) s)");
    CHECK(inner.stmts[4]->kind == StmtKind::Assign);
    REQUIRE(b.result != nullptr);
    CHECK(sx(b.result.get()) == "d");
    CHECK(b.result->loc.line == 12);
    CHECK(b.result->loc.col == 5);
    CHECK(sx_stmt(&p.stmt(2)) == "(call menger 4)");
    // The bound form.
    CHECK(ex("field(bound = 2) (p) -> length(p) - 1") == "(field bound=2 (p) (- (call length p) 1))");
    CHECK(ex("field(2)(q) -> q.x") == "(field 2 (q) (.x q))");
    CHECK(ex("field ( p ) -> p") == "(field (p) p)");
}

// ----------------------------------------------------------------------- expressions

TEST_CASE("operator precedence and associativity", "[parser]") {
    CHECK(ex("1 + 2 * 3") == "(+ 1 (* 2 3))");
    CHECK(ex("1 * 2 + 3") == "(+ (* 1 2) 3)");
    CHECK(ex("1 - 2 - 3") == "(- (- 1 2) 3)");
    CHECK(ex("8 / 4 / 2 % 3") == "(% (/ (/ 8 4) 2) 3)");
    CHECK(ex("-a.x") == "(neg (.x a))");
    CHECK(ex("-a * b") == "(* (neg a) b)");
    CHECK(ex("!a && b") == "(&& (not a) b)");
    CHECK(ex("- -a") == "(neg (neg a))");
    CHECK(ex("a ? b : c ? d : e") == "(? a b (? c d e))");
    CHECK(ex("a ? b ? c : d : e") == "(? a (? b c d) e)");
    CHECK(ex("a || b && c") == "(|| a (&& b c))");
    CHECK(ex("a && b || c") == "(|| (&& a b) c)");
    CHECK(ex("a < b < c") == "(< (< a b) c)");
    CHECK(ex("a == b != c") == "(!= (== a b) c)");
    CHECK(ex("a <= b + 1") == "(<= a (+ b 1))");
    CHECK(ex("a >= b && c > d") == "(&& (>= a b) (> c d))");
    CHECK(ex("1 + 2 == 3 ? x : y") == "(? (== (+ 1 2) 3) x y)");
    CHECK(ex("(1 + 2) * 3") == "(* (+ 1 2) 3)");
    CHECK(ex("a-1") == "(- a 1)");
    CHECK(ex("a*-1") == "(* a (neg 1))");
    CHECK(ex("k > 0 ? sphere(1) : { box(1); }") == "(? (> k 0) (call sphere 1) {(call box 1); })");
    // A modifier's target that begins with a name or a number is a whole expression.
    CHECK(ex("translate(v) box(1) + 1") == "(apply (call translate v) (+ (call box 1) 1))");
    CHECK(ex("translate(v) k > 1 ? sphere(1) : box(1)") == "(apply (call translate v) (? (> k 1) (call sphere 1) (call box 1)))");
    CHECK(ex("translate(v) 1 > 0 ? a : b") == "(apply (call translate v) (? (> 1 0) a b))");
    CHECK(ex("c ? translate(v) a : b") == "(? c (apply (call translate v) a) b)");
    CHECK(ex("f(translate(v) a, b)") == "(call f (apply (call translate v) a) b)");
}

TEST_CASE("postfix: calls, indexing, swizzles", "[parser]") {
    CHECK(ex("box(2)(p)") == "(call (call box 2) p)");
    CHECK(ex("f()") == "(call f)");
    CHECK(ex("f(1, 2,)") == "(call f 1 2)");
    CHECK(ex("torus(major = 1, minor = 0.2)") == "(call torus major=1 minor=0.2)");
    CHECK(ex("f(1, b = 2, 3)") == "(call f 1 b=2 3)");
    CHECK(ex("f(a == b)") == "(call f (== a b))");
    CHECK(ex("v[0]") == "(index v 0)");
    CHECK(ex("m[1][2]") == "(index (index m 1) 2)");
    CHECK(ex("p.xyz") == "(.xyz p)");
    CHECK(ex("c.rgba") == "(.rgba c)");
    CHECK(ex("p.zyx.x") == "(.x (.zyx p))");
    CHECK(ex("v[0].x") == "(.x (index v 0))");
    CHECK(ex("f(p).xy") == "(.xy (call f p))");
    CHECK(ex("(a + b).x") == "(.x (+ a b))");
    CHECK(ex("[1, 2, 3].z") == "(.z [1 2 3])");
    // `.5` after an expression is a number, not a swizzle (and two expressions in a row).
    CHECK(error_of("x = a .5;") == "1:6: expected ';' after the statement");
}

TEST_CASE("vectors and ranges", "[parser]") {
    CHECK(ex("[0 : 2]") == "(range 0 2)");
    CHECK(ex("[0:0.5:2]") == "(range 0 0.5 2)");
    CHECK(ex("[-n : 2 * n]") == "(range (neg n) (* 2 n))");
    CHECK(ex("[a ? 1 : 2 : 3]") == "(range (? a 1 2) 3)");
    CHECK(ex("[1, 2, 3]") == "[1 2 3]");
    CHECK(ex("[1, 2, 3, 4,]") == "[1 2 3 4]");
    CHECK(ex("[x]") == "[x]");
    CHECK(ex("[]") == "[]");
    CHECK(ex("[[1, 2], [3, 4]]") == "[[1 2] [3 4]]");
    Parsed p = parse_text("x = [0 : 2];");
    const Expr& r = *p.stmt(0).value;
    REQUIRE(r.kind == ExprKind::Range);
    REQUIRE(r.elems.size() == 3);
    CHECK(r.elems[1] == nullptr);
    CHECK(r.loc.col == 5);
}

TEST_CASE("numbers", "[parser]") {
    auto num = [](const std::string& s) {
        Parsed p = parse_text("x = " + s + ";");
        const Expr& e = *p.stmt(0).value;
        REQUIRE(e.kind == ExprKind::Number);
        return e.number;
    };
    CHECK(num("1") == 1.0);
    CHECK(num("1.5") == 1.5);
    CHECK(num(".5") == 0.5);
    CHECK(num("1e-3") == 0.001);
    CHECK(num("2.") == 2.0);
    CHECK(num("1E+2") == 100.0);
    CHECK(num("2.5e1") == 25.0);
    CHECK(num("007") == 7.0);
    CHECK(ex("-1") == "(neg 1)");
    CHECK(error_of("x = 1e;") == "1:7: expected digits in the number's exponent");
    CHECK(error_of("x = 1e400;") == "1:5: number '1e400' is out of range");
}

TEST_CASE("strings and escapes", "[parser]") {
    auto str = [](const std::string& s) {
        Parsed p = parse_text("x = " + s + ";");
        const Expr& e = *p.stmt(0).value;
        REQUIRE(e.kind == ExprKind::String);
        return e.text;
    };
    CHECK(str(R"("plain")") == "plain");
    CHECK(str(R"("")") == "");
    CHECK(str(R"("say \"hi\"")") == "say \"hi\"");
    CHECK(str(R"("back\\slash")") == "back\\slash");
    CHECK(str(R"("a\nb\tc")") == "a\nb\tc");
    CHECK(str(R"("ünïcødé ✓")") == "ünïcødé ✓");
    CHECK(str(R"("// not a comment /*")") == "// not a comment /*");
    CHECK(sx1(R"(camera(projection = "orthographic");)") == "(call camera projection=\"orthographic\")");
}

TEST_CASE("comments and whitespace", "[parser]") {
    Parsed p = parse_text("// leading\n/* block\n comment */ sphere(1); // trailing\n"
                          "box(/* inline */ 2) /* between */ ;\r\n\ttorus(1, /**/ 0.2);//\n/***/");
    REQUIRE(p.size() == 3);
    CHECK(sx_stmt(&p.stmt(0)) == "(call sphere 1)");
    CHECK(p.stmt(0).loc.line == 3);
    CHECK(p.stmt(0).loc.col == 13);
    CHECK(sx_stmt(&p.stmt(1)) == "(call box 2)");
    CHECK(p.stmt(2).loc.line == 5);
    CHECK(p.stmt(2).loc.col == 2);
    CHECK(ex("a /* x */ / b") == "(/ a b)");
    CHECK(ex("a//x\n+ b") == "(+ a b)");
    CHECK(parse_text("").size() == 0);
    CHECK(parse_text("  \n// only a comment").size() == 0);
    CHECK(sx1("\xEF\xBB\xBFsphere(1);") == "(call sphere 1)");  // a UTF-8 byte order mark
}

TEST_CASE("keywords are not prefixes of names", "[parser]") {
    CHECK(ex("letter + format + iffy + forest + trueish + variable + definition + elsewhere + imports + fieldx") ==
          "(+ (+ (+ (+ (+ (+ (+ (+ (+ letter format) iffy) forest) trueish) variable) definition) elsewhere) imports) "
          "fieldx)");
    CHECK(ex("true && !false") == "(&& true (not false))");
    CHECK(sx1("let letter = 1;") == "let letter = 1");
    CHECK(error_of("let for = 1;") == "1:5: expected a name after 'let' ('for' is a keyword)");
    CHECK(error_of("x = let;") == "1:5: expected an expression after '='");
}

TEST_CASE("modifier chains", "[parser]") {
    CHECK(sx1("material(gold) torus(0.8, 0.25);") == "(apply (call material gold) (call torus 0.8 0.25))");
    CHECK(sx1("for (i = [0 : 2]) translate([i, 0, 0]) rotate(x = 90 + 30 * i) material(gold) torus(0.8, 0.25);") ==
          "for (i (range 0 2)) (apply (call translate [i 0 0]) (apply (call rotate x=(+ 90 (* 30 i))) "
          "(apply (call material gold) (call torus 0.8 0.25))))");
    // Targets: a name, a block, a for, an if, a field.
    CHECK(sx1("translate(v) s;") == "(apply (call translate v) s)");
    CHECK(sx1("scale(2) union { a; b; }") == "(apply (call scale 2) (apply union {a; b; }))");
    CHECK(sx1("translate(v) for (i = [0 : 2]) rotate(y = i) box(1);") ==
          "(apply (call translate v) (for (i (range 0 2)) (apply (call rotate y=i) (call box 1))))");
    CHECK(sx1("translate(v) if (c) box(1) else sphere(1);") ==
          "(apply (call translate v) (if c (call box 1) (call sphere 1)))");
    CHECK(sx1("translate(v) if (c) box(1);") == "(apply (call translate v) (if c (call box 1)))");
    CHECK(sx1("material(m) field (p) -> length(p) - 1;") ==
          "(apply (call material m) (field (p) (- (call length p) 1)))");
    CHECK(sx1("let s = translate([1, 0, 0]) sphere(1);") ==
          "let s = (apply (call translate [1 0 0]) (call sphere 1))");
    CHECK(sx1("f(translate(v) box(1), 2);") == "(call f (apply (call translate v) (call box 1)) 2)");
    // Apply positions: the modifier's first character.
    Parsed p = parse_text("  translate(v)\n    box(1);");
    const Expr& a = *p.stmt(0).value;
    REQUIRE(a.kind == ExprKind::Apply);
    CHECK(a.loc.line == 1);
    CHECK(a.loc.col == 3);
    CHECK(a.rhs->loc.line == 2);
    CHECK(a.rhs->loc.col == 5);
    // Only a call or a name modifies.
    CHECK(error_of("v.x sphere(1);") == "1:5: only a call or a name can be applied to a shape (is a ';' missing?)");
    CHECK(error_of("x = 1 sphere(1);") == "1:6: expected ';' after the statement");
}

TEST_CASE("for and if as expressions", "[parser]") {
    CHECK(ex("if (a) 1 else 2") == "(if a 1 2)");
    Parsed p = parse_text("x = if (a) 1;");
    const Expr& e = *p.stmt(0).value;
    REQUIRE(e.kind == ExprKind::If);
    REQUIRE(e.elems.size() == 3);
    CHECK(e.elems[2] == nullptr);
    CHECK(ex("for (i = [0 : 3], j = v) sphere(i)") == "(for (i (range 0 3))(j v) (call sphere i))");
}

// ------------------------------------------------------------------------ statements

TEST_CASE("statements", "[parser]") {
    CHECK(sx1("var d = 1;") == "var d = 1");
    CHECK(sx1("d = max(d, c);") == "d = (call max d c)");
    CHECK(sx1("d == 1;") == "(== d 1)");
    CHECK(sx1(";") == "empty");
    CHECK(sx1("if (a) if (b) x; else y;") == "if a then if b then x else y");
    CHECK(sx1("if (a) { x; } else { y; }") == "if a then {x; } else {y; }");
    CHECK(sx1("if (a) union { x; }") == "if a then (apply union {x; })");
    CHECK(sx1("for (i = [0:2]) { sphere(i); }") == "for (i (range 0 2)) {(call sphere i); }");
    CHECK(sx1("for (i = v) { }") == "for (i v) {}");
    CHECK(sx1("{ a; b; }") == "{a; b; }");
    CHECK(sx1("def f(x) { sphere(x); box(x); }") == "def f(x) = {(call sphere x); (call box x); }");
    CHECK(sx1("def g() = 1;") == "def g() = 1");
    CHECK(sx1("def h(a, b = 2,) = a;") == "def h(a, b = 2) = a");
    CHECK(sx1(R"(import "a b/c.sdf";)") == "import \"a b/c.sdf\"");
}

TEST_CASE("statements ending with a block need no semicolon", "[parser]") {
    Parsed p = parse_text("difference { box(1); sphere(0.6); }\nsphere(2);\n"
                          "union { a; } ;\n"
                          "for (i = [0:1]) translate([i,0,0]) { box(1); } b;\n"
                          "{ c; } d;\n"
                          "smooth_union(0.3) { e; } /* c */ f;");
    REQUIRE(p.size() == 9);
    CHECK(sx_stmt(&p.stmt(0)) == "(apply difference {(call box 1); (call sphere 0.6); })");
    CHECK(sx_stmt(&p.stmt(1)) == "(call sphere 2)");
    CHECK(sx_stmt(&p.stmt(2)) == "(apply union {a; })");  // the ';' belongs to it
    CHECK(sx_stmt(&p.stmt(3)) == "for (i (range 0 1)) (apply (call translate [i 0 0]) {(call box 1); })");
    CHECK(sx_stmt(&p.stmt(4)) == "b");
    CHECK(sx_stmt(&p.stmt(5)) == "{c; }");
    CHECK(sx_stmt(&p.stmt(6)) == "d");
    CHECK(sx_stmt(&p.stmt(7)) == "(apply (call smooth_union 0.3) {e; })");
    CHECK(sx_stmt(&p.stmt(8)) == "f");
    // A let needs its ';' even after a block.
    CHECK(error_of("let u = { a; }\nb;") == "1:15: expected ';' after the statement");
    // ... and so does a parenthesised block.
    CHECK(error_of("({ a; })\nb;") == "1:9: expected ';' after the statement");
}

TEST_CASE("block results", "[parser]") {
    CHECK(ex("{ d }") == "{=> d}");
    CHECK(ex("{ sphere(1); box(1) }") == "{(call sphere 1); => (call box 1)}");
    CHECK(ex("{ let a = 1; a + 1 }") == "{let a = 1; => (+ a 1)}");
    CHECK(ex("{ a; }") == "{a; }");
    CHECK(ex("{}") == "{}");
    CHECK(ex("{ ; }") == "{empty; }");
    CHECK(ex("{ union { a; } }") == "{(apply union {a; }); }");
    CHECK(ex("{ { 1 } }") == "{{=> 1}; }");
    // Only directly inside a block: an if body still needs its ';'.
    CHECK(error_of("x = { if (a) b };") == "1:15: expected ';' after the statement");
    Parsed p = parse_text("x = {\n  1\n};");
    const Expr& b = *p.stmt(0).value;
    REQUIRE(b.kind == ExprKind::BlockExpr);
    CHECK(b.loc.col == 5);
    CHECK(b.block->loc.col == 5);
    CHECK(b.block->result->loc.line == 2);
}

TEST_CASE("locations", "[parser]") {
    Parsed p = parse_text("let a = 1;\n  sphere(r = 2, 3);\r\nx = (1 + 2) * 3;\n\t f(g)(h);");
    const Stmt& call = p.stmt(1);
    CHECK(call.loc.line == 2);
    CHECK(call.loc.col == 3);
    CHECK(call.loc.file == p.file.get());
    const Expr& c = *call.value;
    CHECK(c.loc.col == 3);
    CHECK(c.callee->loc.col == 3);
    REQUIRE(c.args.size() == 2);
    CHECK(c.args[0].loc.col == 10);  // the name of a named argument
    CHECK(c.args[0].value->loc.col == 14);
    CHECK(c.args[1].loc.col == 17);  // the value of a positional one
    const Stmt& assign = p.stmt(2);
    CHECK(assign.loc.line == 3);
    CHECK(assign.name_loc.col == 1);
    const Expr& mul = *assign.value;
    CHECK(mul.loc.col == 13);       // a binary operation: its operator
    CHECK(mul.lhs->loc.col == 8);
    CHECK(mul.rhs->loc.col == 15);
    CHECK(assign.value->kind == ExprKind::Binary);
    Parsed q = parse_text("(a + b) * c ? x : y;\n(a).x;\n(f)(1);");
    CHECK(q.stmt(0).loc.col == 1);          // statements start at the '('
    CHECK(q.stmt(0).value->loc.col == 1);   // and so does the ternary (its first character)
    CHECK(q.stmt(1).value->loc.col == 1);   // the swizzle
    CHECK(q.stmt(2).value->loc.col == 1);   // the call: its callee's first character
    CHECK(error_of("(m) box(1);") == "1:4: expected ';' after the statement");  // modifiers are names or calls
    const Expr& fgh = *p.stmt(3).value;
    CHECK(fgh.loc.line == 4);
    CHECK(fgh.loc.col == 3);
    CHECK(fgh.callee->loc.col == 3);
    CHECK(p.module->file == p.file.get());
}

// ------------------------------------------------------- fast paths (sdf_grammar.hpp "Speed")

TEST_CASE("numbers: the fast path rounds exactly as from_chars", "[parser]") {
    for (const char* s : {"0.1", "0.3", "2.675", "1.", "0.000001", "99999.99999", "123456789012345", "1234567890123456",
                          "9007199254740993", ".000000000000001", "00000000000001.5", "4.35", "1e-7", "12345.678e3"}) {
        double expect = 0;
        std::from_chars(s, s + std::strlen(s), expect);
        Parsed p = parse_text(std::string("x = ") + s + ";");
        INFO(s);
        CHECK(p.stmt(0).value->number == expect);
    }
}

TEST_CASE("guards: what is not an operator, postfix or target", "[parser]") {
    CHECK(error_of("x = a -> b;") == "1:6: expected ';' after the statement");
    CHECK(error_of("x = a - > b;") == "1:9: expected an expression after the operator");
    CHECK(error_of("x = a !b;") == "1:6: expected ';' after the statement");
    CHECK(error_of("x = a = = b;") == "1:6: expected ';' after the statement");
    CHECK(error_of("x = a == = b;") == "1:10: expected an expression after the operator");
    CHECK(error_of("x = a & & b;") == "1:7: unexpected character '&' (did you mean '&&'?)");
    CHECK(error_of("x = a ?;") == "1:8: expected an expression after '?'");
    CHECK(error_of("x = f(a) . 5;") == "1:11: unexpected character ' '");
    CHECK(error_of("translate(v) !a;") == "1:13: expected ';' after the statement");
    CHECK(error_of("a b -> c;") == "1:4: expected ';' after the statement");
    CHECK(error_of("x = - - -;") == "1:10: expected an expression after '-'");
    CHECK(sx1("translate(v) -1;") == "(- (call translate v) 1)");
    CHECK(ex("--a") == "(neg (neg a))");
    CHECK(ex("!!a") == "(not (not a))");
    CHECK(ex("v[1](2).x") == "(.x (call (index v 1) 2))");
    CHECK(ex("iff + for_ + true1 + _let + let_ + LET + imports + Field") ==
          "(+ (+ (+ (+ (+ (+ (+ iff for_) true1) _let) let_) LET) imports) Field)");
}

TEST_CASE("whitespace and comments: every form", "[parser]") {
    CHECK(sx1("let\tx\v=\f1;") == "let x = 1");
    CHECK(parse_text("a; //").size() == 1);
    CHECK(parse_text("a; //\r\nb;").size() == 2);
    CHECK(parse_text("a//c\n;").size() == 1);
    CHECK(parse_text("a/**//**/;").size() == 1);
    CHECK(parse_text("a /* * / */ ;").size() == 1);
    CHECK(ex("1 /*/ 2 */ / 2") == "(/ 1 2)");
    CHECK(error_of("a; /*") == "1:4: unterminated comment");
    CHECK(error_of("a; /* */ */") == "1:10: expected a statement");
    Parsed p = parse_text("a; // x\r\n  /* y\n z */ b;");
    CHECK(p.stmt(1).loc.line == 3);
    CHECK(p.stmt(1).loc.col == 7);
}

TEST_CASE("a long script: locations and repeated parses", "[parser]") {
    std::string text;
    for (int i = 0; i < 3000; ++i)
        text += i % 3 == 0 ? fmt::format("translate([{}, 0, 1]) sphere(s);\n", i)
                : i % 3 == 1 ? fmt::format("  let v{} = [{}, 1] * 0.5; // note\n", i, i)
                             : fmt::format("rotate(y = {}) /* c */ box([1, 2, 3]);\n", i);
    Parsed a = parse_text(text);
    REQUIRE(a.size() == 3000);
    CHECK(a.stmt(2999).loc.line == 3000);
    CHECK(a.stmt(2998).loc.col == 3);
    CHECK(a.stmt(2998).name == "v2998");
    CHECK(a.stmt(2998).name_loc.col == 7);
    const Expr& v = *a.stmt(2998).value;  // [2998, 1] * 0.5: the operator's location
    CHECK(v.loc.line == 2999);
    CHECK(v.loc.col == 25);
    CHECK(sx_stmt(&a.stmt(1500)) == "(apply (call translate [1500 0 1]) (call sphere s))");
    // Parsing again (reusing freed nodes) builds the same tree.
    std::string first = dump(*a.module);
    a.module.reset();
    Parsed b = parse_text(text);
    CHECK(dump(*b.module) == first);
}

TEST_CASE("trees may be built and freed on different threads", "[parser]") {
    const std::string text = "translate([1, 0, 2]) sphere(s);\nlet v = [1, 2, 3] * 0.5;\ndef f(a, b = 2) { a + b }\n";
    SourceFile f("t.sdf", text);
    std::vector<std::unique_ptr<Module>> kept;
    for (int round = 0; round < 4; ++round) {
        std::thread t([&] {
            for (int i = 0; i < 20; ++i) parse(f);                 // built and freed here
            kept.push_back(parse(f));                              // freed on the main thread
            if (kept.size() > 2) kept.erase(kept.begin());         // built on the main thread, freed here
        });
        t.join();
        kept.push_back(parse(f));
    }
    for (const auto& m : kept) CHECK(dump(*m) == dump(*parse(f)));
}

// --------------------------------------------------------------------------- dump

TEST_CASE("dump lists the tree", "[parser][dump]") {
    Parsed p = parse_text("let r = 0.5;\n"
                          "def ring(R, t = 0.1) = rotate(x = 90) torus(R, t);\n"
                          "if (r > 0.3) sphere(r); else box(-r);\n"
                          "for (i = [0 : 0.5 : 2]) union { ring(i); v.xy[1]; }\n"
                          "import \"lib/a.sdf\";\n"
                          "x = field(bound = 2) (p) -> { var d = p.x; d };\n"
                          "f(1)(p) ? true : \"s\";\n");
    CHECK(dump(*p.module) ==
          "let r @1:1\n"
          "  number 0.5\n"
          "def ring @2:1\n"
          "  param R\n"
          "  param t =\n"
          "    number 0.1\n"
          "  apply\n"
          "    call rotate\n"
          "      arg x =\n"
          "        number 90\n"
          "    call torus\n"
          "      arg\n"
          "        ident R\n"
          "      arg\n"
          "        ident t\n"
          "if @3:1\n"
          "  binary >\n"
          "    ident r\n"
          "    number 0.3\n"
          "  then\n"
          "    expr @3:14\n"
          "      call sphere\n"
          "        arg\n"
          "          ident r\n"
          "  else\n"
          "    expr @3:30\n"
          "      call box\n"
          "        arg\n"
          "          unary -\n"
          "            ident r\n"
          "for @4:1\n"
          "  binding i\n"
          "    range with step\n"
          "      number 0\n"
          "      number 0.5\n"
          "      number 2\n"
          "  expr @4:25\n"
          "    apply\n"
          "      ident union\n"
          "      block\n"
          "        expr @4:33\n"
          "          call ring\n"
          "            arg\n"
          "              ident i\n"
          "        expr @4:42\n"
          "          index\n"
          "            swizzle .xy\n"
          "              ident v\n"
          "            number 1\n"
          "import \"lib/a.sdf\" @5:1\n"
          "assign x @6:1\n"
          "  field (p)\n"
          "    arg bound =\n"
          "      number 2\n"
          "    block\n"
          "      var d @6:31\n"
          "        swizzle .x\n"
          "          ident p\n"
          "      result\n"
          "        ident d\n"
          "expr @7:1\n"
          "  ternary\n"
          "    call\n"
          "      callee\n"
          "        call f\n"
          "          arg\n"
          "            number 1\n"
          "      arg\n"
          "        ident p\n"
          "    bool true\n"
          "    string \"s\"\n");
}
