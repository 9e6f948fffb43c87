// `sdfc compile --emit ast`: one node per line, children indented by two spaces (up to a
// depth of 40; deeper lines say their depth).
// Statements end with their position `@line:col`; expressions are listed without positions
// so that golden listings survive edits that only move code. Labels (`then`, `else`,
// `callee`, `result`) are lines of their own where the role of a child is not obvious
// from its place.
//
//   let gold @6:1
//     call material
//       arg color =
//         vector
//           number 0.9
//   ...
#include <algorithm>
#include <fmt/format.h>

#include "lang/ast.hpp"

namespace sdfc::ast {
namespace {

const char* bin_op_text(BinOp op) {
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

std::string quote(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\', out += c;
        else if (c == '\n') out += "\\n";
        else if (c == '\t') out += "\\t";
        else out += c;
    }
    return out + "\"";
}

struct Dumper {
    std::string out;

    // Past kMaxIndent levels the indent stays put and the line says its depth: deep input
    // (thousands of nested terms) would otherwise print output quadratic in its size.
    static constexpr int kMaxIndent = 40;
    void line(int depth, const std::string& text) {
        out.append(static_cast<size_t>(std::min(depth, kMaxIndent)) * 2, ' ');
        if (depth > kMaxIndent) out += fmt::format("[depth {}] ", depth);
        out += text;
        out += '\n';
    }
    static std::string at(const Loc& l) { return fmt::format("@{}:{}", l.line, l.col); }

    void args(const std::vector<Arg>& as, int d) {
        for (const auto& a : as) {
            line(d, a.name.empty() ? std::string("arg") : fmt::format("arg {} =", a.name));
            expr(a.value.get(), d + 1);
        }
    }

    void bindings(const std::vector<ForBinding>& bs, int d) {
        for (const auto& b : bs) {
            line(d, fmt::format("binding {}", b.name));
            expr(b.iterable.get(), d + 1);
        }
    }

    void block(const Block& b, int d) {
        for (const auto& s : b.stmts) stmt(s.get(), d);
        if (b.result) {
            line(d, "result");
            expr(b.result.get(), d + 1);
        }
    }

    void expr(const Expr* e, int d) {
        if (!e) {
            line(d, "(none)");
            return;
        }
        check_stack(e->loc);  // trees as tall as the parser allows (see compiler/base/source.hpp)
        switch (e->kind) {
            case ExprKind::Number: line(d, fmt::format("number {}", e->number)); break;
            case ExprKind::Bool: line(d, e->boolean ? "bool true" : "bool false"); break;
            case ExprKind::String: line(d, "string " + quote(e->text)); break;
            case ExprKind::Ident: line(d, "ident " + e->text); break;
            case ExprKind::Vector:
                line(d, "vector");
                for (const auto& el : e->elems) expr(el.get(), d + 1);
                break;
            case ExprKind::Range:
                line(d, e->elems[1] ? "range with step" : "range");
                for (const auto& el : e->elems)
                    if (el) expr(el.get(), d + 1);
                break;
            case ExprKind::Unary:
                line(d, e->un_op == UnOp::Neg ? "unary -" : "unary !");
                expr(e->lhs.get(), d + 1);
                break;
            case ExprKind::Binary:
                line(d, fmt::format("binary {}", bin_op_text(e->bin_op)));
                expr(e->lhs.get(), d + 1);
                expr(e->rhs.get(), d + 1);
                break;
            case ExprKind::Ternary:
                line(d, "ternary");
                for (const auto& el : e->elems) expr(el.get(), d + 1);
                break;
            case ExprKind::Call:
                if (e->callee && e->callee->kind == ExprKind::Ident) {
                    line(d, "call " + e->callee->text);
                } else {
                    line(d, "call");
                    line(d + 1, "callee");
                    expr(e->callee.get(), d + 2);
                }
                args(e->args, d + 1);
                break;
            case ExprKind::Index:
                line(d, "index");
                expr(e->lhs.get(), d + 1);
                expr(e->rhs.get(), d + 1);
                break;
            case ExprKind::Swizzle:
                line(d, "swizzle ." + e->text);
                expr(e->lhs.get(), d + 1);
                break;
            case ExprKind::Apply:
                line(d, "apply");
                expr(e->lhs.get(), d + 1);
                expr(e->rhs.get(), d + 1);
                break;
            case ExprKind::BlockExpr:
                line(d, "block");
                if (e->block) block(*e->block, d + 1);
                break;
            case ExprKind::Field:
                line(d, fmt::format("field ({})", e->text));
                args(e->args, d + 1);
                expr(e->body.get(), d + 1);
                break;
            case ExprKind::If:
                line(d, "if");
                expr(e->elems[0].get(), d + 1);
                line(d + 1, "then");
                expr(e->elems[1].get(), d + 2);
                if (e->elems.size() > 2 && e->elems[2]) {
                    line(d + 1, "else");
                    expr(e->elems[2].get(), d + 2);
                }
                break;
            case ExprKind::For:
                line(d, "for");
                bindings(e->bindings, d + 1);
                if (e->block) block(*e->block, d + 1);
                if (e->body) expr(e->body.get(), d + 1);
                break;
        }
    }

    void stmt(const Stmt* s, int d) {
        check_stack(s->loc);
        switch (s->kind) {
            case StmtKind::Let:
            case StmtKind::Var:
            case StmtKind::Assign: {
                const char* kw = s->kind == StmtKind::Let ? "let" : s->kind == StmtKind::Var ? "var" : "assign";
                line(d, fmt::format("{} {} {}", kw, s->name, at(s->loc)));
                expr(s->value.get(), d + 1);
                break;
            }
            case StmtKind::Def:
                line(d, fmt::format("def {} {}", s->name, at(s->loc)));
                for (const auto& p : s->params) {
                    line(d + 1, p.default_value ? fmt::format("param {} =", p.name) : "param " + p.name);
                    if (p.default_value) expr(p.default_value.get(), d + 2);
                }
                expr(s->value.get(), d + 1);
                break;
            case StmtKind::Import: line(d, fmt::format("import {} {}", quote(s->name), at(s->loc))); break;
            case StmtKind::Expr:
                line(d, "expr " + at(s->loc));
                expr(s->value.get(), d + 1);
                break;
            case StmtKind::If:
                line(d, "if " + at(s->loc));
                expr(s->value.get(), d + 1);
                line(d + 1, "then");
                stmt(s->then_branch.get(), d + 2);
                if (s->else_branch) {
                    line(d + 1, "else");
                    stmt(s->else_branch.get(), d + 2);
                }
                break;
            case StmtKind::For:
                line(d, "for " + at(s->loc));
                bindings(s->bindings, d + 1);
                stmt(s->body.get(), d + 1);
                break;
            case StmtKind::Empty: line(d, "empty " + at(s->loc)); break;
        }
    }
};

}  // namespace

std::string dump(const Module& m) {
    Dumper d;
    for (const auto& s : m.stmts) d.stmt(s.get(), 0);
    return d.out;
}

}  // namespace sdfc::ast
