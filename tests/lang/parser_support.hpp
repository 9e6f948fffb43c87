// Helpers of the parser tests (test_parser*.cpp): parse a string, the first syntax error
// as "line:col: message", and compact s-expressions of the tree to check its structure.
#pragma once
#include <catch2/catch.hpp>

#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lang/ast.hpp"

namespace sdfc::test {

using namespace sdfc::ast;

struct Parsed {
    std::unique_ptr<SourceFile> file;
    std::unique_ptr<Module> module;
    const Stmt& stmt(size_t i) const { return *module->stmts.at(i); }
    size_t size() const { return module->stmts.size(); }
};

inline Parsed parse_text(const std::string& text, const ParseOptions& opts = {}) {
    Parsed p;
    p.file = std::make_unique<SourceFile>("test.sdf", text);
    p.module = parse(*p.file, opts);
    return p;
}

// The first diagnostic of a failing parse, as "line:col: message".
inline std::string error_of(const std::string& text, const ParseOptions& opts = {}) {
    SourceFile f("test.sdf", text);
    try {
        parse(f, opts);
    } catch (const CompileError& e) {
        const Diagnostic& d = e.diagnostics().at(0);
        return fmt::format("{}:{}: {}", d.loc.line, d.loc.col, d.message);
    }
    return "no error";
}

inline const char* op_name(BinOp op) {
    switch (op) {
        case BinOp::Or: return "||";
        case BinOp::And: return "&&";
        case BinOp::Eq: return "==";
        case BinOp::Ne: return "!=";
        case BinOp::Lt: return "<";
        case BinOp::Le: return "<=";
        case BinOp::Gt: return ">";
        case BinOp::Ge: return ">=";
        case BinOp::Add: return "+";
        case BinOp::Sub: return "-";
        case BinOp::Mul: return "*";
        case BinOp::Div: return "/";
        case BinOp::Mod: return "%";
    }
    return "?";
}

inline std::string sx(const Expr* e);
inline std::string sx_stmt(const Stmt* s);

inline std::string sx_args(const std::vector<Arg>& args) {
    std::string out;
    for (const auto& a : args) out += " " + (a.name.empty() ? "" : a.name + "=") + sx(a.value.get());
    return out;
}

inline std::string sx_block(const Block& b) {
    std::string out = "{";
    for (const auto& s : b.stmts) out += sx_stmt(s.get()) + "; ";
    if (b.result) out += "=> " + sx(b.result.get());
    return out + "}";
}

inline std::string sx_bindings(const std::vector<ForBinding>& bs) {
    std::string out;
    for (const auto& b : bs) out += fmt::format("({} {})", b.name, sx(b.iterable.get()));
    return out;
}

// A compact s-expression of an expression, to check structure.
inline std::string sx(const Expr* e) {
    if (!e) return "null";
    switch (e->kind) {
        case ExprKind::Number: return fmt::format("{}", e->number);
        case ExprKind::Bool: return e->boolean ? "true" : "false";
        case ExprKind::String: return "\"" + e->text + "\"";
        case ExprKind::Ident: return e->text;
        case ExprKind::Vector: {
            std::string out = "[";
            for (size_t i = 0; i < e->elems.size(); ++i) out += (i ? " " : "") + sx(e->elems[i].get());
            return out + "]";
        }
        case ExprKind::Range:
            return e->elems[1] ? fmt::format("(range {} {} {})", sx(e->elems[0].get()), sx(e->elems[1].get()),
                                             sx(e->elems[2].get()))
                               : fmt::format("(range {} {})", sx(e->elems[0].get()), sx(e->elems[2].get()));
        case ExprKind::Unary: return fmt::format("({} {})", e->un_op == UnOp::Neg ? "neg" : "not", sx(e->lhs.get()));
        case ExprKind::Binary: return fmt::format("({} {} {})", op_name(e->bin_op), sx(e->lhs.get()), sx(e->rhs.get()));
        case ExprKind::Ternary:
            return fmt::format("(? {} {} {})", sx(e->elems[0].get()), sx(e->elems[1].get()), sx(e->elems[2].get()));
        case ExprKind::Call: return fmt::format("(call {}{})", sx(e->callee.get()), sx_args(e->args));
        case ExprKind::Index: return fmt::format("(index {} {})", sx(e->lhs.get()), sx(e->rhs.get()));
        case ExprKind::Swizzle: return fmt::format("(.{} {})", e->text, sx(e->lhs.get()));
        case ExprKind::Apply: return fmt::format("(apply {} {})", sx(e->lhs.get()), sx(e->rhs.get()));
        case ExprKind::BlockExpr: return sx_block(*e->block);
        case ExprKind::Field: return fmt::format("(field{} ({}) {})", sx_args(e->args), e->text, sx(e->body.get()));
        case ExprKind::If:
            return e->elems[2] ? fmt::format("(if {} {} {})", sx(e->elems[0].get()), sx(e->elems[1].get()),
                                             sx(e->elems[2].get()))
                               : fmt::format("(if {} {})", sx(e->elems[0].get()), sx(e->elems[1].get()));
        case ExprKind::For: return fmt::format("(for {} {})", sx_bindings(e->bindings), sx(e->body.get()));
    }
    return "?";
}

inline std::string sx_stmt(const Stmt* s) {
    switch (s->kind) {
        case StmtKind::Let: return fmt::format("let {} = {}", s->name, sx(s->value.get()));
        case StmtKind::Var: return fmt::format("var {} = {}", s->name, sx(s->value.get()));
        case StmtKind::Assign: return fmt::format("{} = {}", s->name, sx(s->value.get()));
        case StmtKind::Def: {
            std::string ps;
            for (const auto& p : s->params)
                ps += (ps.empty() ? "" : ", ") + p.name + (p.default_value ? " = " + sx(p.default_value.get()) : "");
            return fmt::format("def {}({}) = {}", s->name, ps, sx(s->value.get()));
        }
        case StmtKind::Import: return fmt::format("import \"{}\"", s->name);
        case StmtKind::Expr: return sx(s->value.get());
        case StmtKind::If:
            return s->else_branch ? fmt::format("if {} then {} else {}", sx(s->value.get()), sx_stmt(s->then_branch.get()),
                                                sx_stmt(s->else_branch.get()))
                                  : fmt::format("if {} then {}", sx(s->value.get()), sx_stmt(s->then_branch.get()));
        case StmtKind::For: return fmt::format("for {} {}", sx_bindings(s->bindings), sx_stmt(s->body.get()));
        case StmtKind::Empty: return "empty";
    }
    return "?";
}

// The s-expression of a one-statement script.
inline std::string sx1(const std::string& text) {
    Parsed p = parse_text(text);
    REQUIRE(p.size() == 1);
    return sx_stmt(&p.stmt(0));
}

// An expression in a statement of its own.
inline std::string ex(const std::string& expr) { return sx1("x = " + expr + ";").substr(4); }

}  // namespace sdfc::test
