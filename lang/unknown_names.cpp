// Unknown names in code that never ran (a def never called, a branch not taken): the
// interpreter resolves names as it runs, so such a typo would wait for the day the code
// runs. After a run without errors, every name that is used anywhere but bound nowhere
// (no let, var, def, parameter, for, field parameter in any of the files, no built-in)
// can only be in code that did not run: a warning, with the same hints as the error.
#include <algorithm>
#include <string_view>
#include <unordered_set>

#include <fmt/format.h>

#include "lang/interp.hpp"

namespace sdfc {
namespace {

class NameWalk {
public:
    std::unordered_set<std::string_view> bound;
    std::vector<const ast::Expr*> uses;  // Ident expressions, in the files' order

    void stmt(const ast::Stmt* s) {
        if (!s || stack_nearly_exhausted()) return;  // (a lint: deep input just stops it)
        switch (s->kind) {
            case ast::StmtKind::Let:
            case ast::StmtKind::Var:
            case ast::StmtKind::Def:
            case ast::StmtKind::Assign:  // (one to an undeclared name is an error of its own when it runs)
                bound.insert(s->name);
                break;
            default:
                break;
        }
        for (const ast::Param& p : s->params) {
            bound.insert(p.name);
            expr(p.default_value.get());
        }
        bindings(s->bindings);
        if (s->kind != ast::StmtKind::Import) expr(s->value.get());
        stmt(s->then_branch.get());
        stmt(s->else_branch.get());
        stmt(s->body.get());
    }

    void expr(const ast::Expr* e) {
        if (!e || stack_nearly_exhausted()) return;
        if (e->kind == ast::ExprKind::Ident) uses.push_back(e);
        if (e->kind == ast::ExprKind::Field) bound.insert(e->text);
        expr(e->lhs.get());
        expr(e->rhs.get());
        for (const auto& x : e->elems) expr(x.get());
        expr(e->callee.get());
        for (const ast::Arg& a : e->args) expr(a.value.get());
        if (e->block) {
            for (const auto& s : e->block->stmts) stmt(s.get());
            expr(e->block->result.get());
        }
        bindings(e->bindings);
        expr(e->body.get());
    }

private:
    void bindings(const std::vector<ast::ForBinding>& bs) {
        for (const ast::ForBinding& b : bs) {
            bound.insert(b.name);
            expr(b.iterable.get());
        }
    }
};

}  // namespace

void warn_unknown_names(const std::deque<std::unique_ptr<ast::Module>>& modules, std::vector<Diagnostic>& warnings) {
    NameWalk w;
    for (const auto& m : modules)
        for (const auto& s : m->stmts) w.stmt(s.get());
    auto constant = [](std::string_view n) { return std::find(std::begin(kConstantNames), std::end(kConstantNames), n) != std::end(kConstantNames); };
    // At most kShown, each with its did-you-mean (a search of every name): 16,000 defs
    // each naming `sphre` took 16 s to check when every one was searched.
    constexpr size_t kShown = 20;
    const std::vector<std::string> names(w.bound.begin(), w.bound.end());
    size_t found = 0;
    const ast::Expr* first_unshown = nullptr;
    for (const ast::Expr* e : w.uses) {
        const std::string& name = e->text;
        if (w.bound.count(name) || constant(name) || find_builtin(name)) continue;
        if (++found > kShown) {
            if (!first_unshown) first_unshown = e;
            continue;
        }
        warnings.push_back({e->loc, unknown_name_message(name, names) + ", in code that has not run (a def never called, a branch not taken)"});
    }
    if (first_unshown)
        warnings.push_back({first_unshown->loc, fmt::format("{} more names bound nowhere, in code that has not run (this is the first)",
                                                            found - kShown)});
}

}  // namespace sdfc
