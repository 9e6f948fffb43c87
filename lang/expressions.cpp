// Expressions, calls of user functions and shapes, and the operators: an expression's
// value, built as nodes of the scene's graph. Statements are in interpreter.cpp.
#include <cctype>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>

#include <fmt/format.h>

#include "compiler/scene/lower.hpp"
#include "lang/habits.hpp"
#include "lang/interp.hpp"

namespace sdfc {

// ---------------------------------------------------------------- expressions

Value Interp::eval(const ast::Expr& e, Env* env) {
    using K = ast::ExprKind;
    check_stack(e.loc);
    g->set_loc(e.loc);
    if (e.kind == K::Apply) return apply(e, env);
    if (e.kind == K::BlockExpr) return eval_block(*e.block, env, env->field_scope);
    return eval_rest(e, env);
}

[[gnu::noinline]] Value Interp::eval_rest(const ast::Expr& e, Env* env) {
    using K = ast::ExprKind;
    switch (e.kind) {
        case K::Number: {
            if (!std::isfinite(float(e.number))) fail(e.loc, "this number is too large for a 32-bit float");
            return Value::number(g->constant(float(e.number)));
        }
        case K::Bool:
            return Value::boolean(g->constant(e.boolean ? 1.0f : 0.0f));
        case K::String: {
            Value v;
            v.t = VT::String;
            v.str = std::make_shared<const std::string>(e.text);
            return v;
        }
        case K::Ident: {
            if (Binding* b = env->find(e.text)) return b->value;
            if (e.text == "time") {
                scene.reads_time = true;
                return Value::number(opts.time ? g->constant(*opts.time) : g->input(Op::Time));
            }
            if (e.text == "pi") return Value::number(g->constant(3.14159265358979f));
            if (e.text == "tau") return Value::number(g->constant(6.28318530717959f));
            if (e.text == "e") return Value::number(g->constant(2.71828182845905f));
            if (const BuiltinInfo* bi = find_builtin(e.text)) {
                Value v;
                v.t = VT::Function;
                v.fn = builtin_callable(bi->id);
                return v;
            }
            if (failed_lets.count(e.text) || failed_import) throw CompileError(std::vector<Diagnostic>{});  // its error is out already
            std::vector<std::string> names;
            if (habit_hint(e.text).empty())  // (else the names are not needed)
                for (Env* s = env; s; s = s->parent)
                    for (const auto& [n, b] : s->vars) names.push_back(n);
            if ((e.text == "module" || e.text == "function") && e.loc.known()) {
                // OpenSCAD's `module NAME(...)`: its uses are not new errors.
                const std::string_view ln = e.loc.file->line(e.loc.line);
                size_t i = e.loc.col - 1;
                if (ln.substr(i, e.text.size()) == e.text) {
                    i += e.text.size();
                    while (i < ln.size() && (ln[i] == ' ' || ln[i] == '\t')) ++i;
                    size_t j = i;
                    while (j < ln.size() && (std::isalnum(static_cast<unsigned char>(ln[j])) || ln[j] == '_')) ++j;
                    if (j > i) failed_lets.insert(std::string(ln.substr(i, j - i)));
                }
            }
            // OpenSCAD hoists a file's assignments; here a let takes effect from its line on.
            for (const auto& mod : modules)
                if (mod->file == e.loc.file)
                    for (const auto& st : mod->stmts)
                        if (st->kind == ast::StmtKind::Let && st->name == e.text && st->name_loc.line > e.loc.line)
                            fail(e.loc, fmt::format("unknown name '{}' here: it is defined below, at line {} (a let takes effect "
                                                    "from its line on; move it above its first use)",
                                                    e.text, st->name_loc.line));
            fail(e.loc, unknown_name_message(e.text, names));
        }
        case K::Vector: {
            std::vector<Value> items;
            // A list comprehension, as OpenSCAD's: `[for (i = [0 : 9]) f(i)]` gives the
            // iterations' values; an `if` without `else` that is false gives none, and a `for`
            // (or an `if` choosing one) inside runs nested: `[for (i = ...) for (j = ...) i * j]`.
            auto keep = [&](const ast::Expr& cond, Env* scope) {
                const std::optional<bool> k = const_truth(eval(cond, scope), cond.loc);
                if (!k) fail(cond.loc, "a list comprehension's condition must be a constant");
                return *k;
            };
            std::function<void(const ast::Expr&, Env*)> generate = [&](const ast::Expr& x, Env* scope) {
                if (x.kind == K::For) {
                    run_for(x.bindings, scope, x.loc, [&](Env* body) {
                        if (x.block) {
                            Value v = eval_block(*x.block, body, false);
                            if (v.t != VT::None) items.push_back(std::move(v));
                            check_list_size(items.size(), e.loc);
                        } else {
                            generate(*x.body, body);
                        }
                    });
                    return;
                }
                const bool has_else = x.kind == K::If && x.elems.size() >= 3 && x.elems[2];
                if (x.kind == K::If && (!has_else || x.elems[1]->kind == K::For || x.elems[2]->kind == K::For)) {
                    if (keep(*x.elems[0], scope)) generate(*x.elems[1], scope);
                    else if (has_else) generate(*x.elems[2], scope);
                    return;
                }
                Value v = eval(x, scope);
                if (v.t == VT::None) return;
                items.push_back(std::move(v));
                check_list_size(items.size(), e.loc);
            };
            for (const auto& el : e.elems) {
                if (el->kind == K::For) {
                    generate(*el, env);
                    continue;
                }
                items.push_back(eval(*el, env));
            }
            return list_value(std::move(items), e.loc);
        }
        case K::Range: {
            Value v;
            v.t = VT::Range;
            v.range.start = const_num(eval(*e.elems[0], env), e.elems[0]->loc, "a range's start");
            v.range.end = const_num(eval(*e.elems[2], env), e.elems[2]->loc, "a range's end");
            v.range.step = 1.0f;
            if (e.elems[1]) {
                v.range.step = const_num(eval(*e.elems[1], env), e.elems[1]->loc, "a range's step");
                if (v.range.step == 0.0f || !std::isfinite(v.range.step)) fail(e.elems[1]->loc, "a range's step must not be zero");
            }
            if (!std::isfinite(v.range.start) || !std::isfinite(v.range.end)) fail(e.loc, "a range's ends must be finite");
            // Written so, [10 : 0] is likely meant as OpenSCAD takes it (the ends swapped); a
            // computed one, [0 : len(list) - 1], is rightly empty.
            auto literal = [&](const ast::Expr* x) {
                return x && (x->kind == K::Number || (x->kind == K::Unary && x->un_op == ast::UnOp::Neg && x->lhs->kind == K::Number));
            };
            if (literal(e.elems[0].get()) && literal(e.elems[2].get()) && (!e.elems[1] || literal(e.elems[1].get())) &&
                v.range.count() == 0) {
                const std::string a = shown_number(v.range.start), z = shown_number(v.range.end);
                warn(e.loc, e.elems[1] ? fmt::format("the range [{} : {} : {}] is empty (its step goes away from "
                                                                          "its end)", a, shown_number(v.range.step), z)
                                                            : fmt::format("the range [{} : {}] is empty (its start is above its end): "
                                                                          "for a count down write [{} : -1 : {}]", a, z, a, z));
            }
            return v;
        }
        case K::Unary:
            return unary(e.un_op, eval(*e.lhs, env), e.loc);
        case K::Binary: {
            if (e.bin_op == ast::BinOp::And || e.bin_op == ast::BinOp::Or) {
                Value a = eval(*e.lhs, env);
                std::optional<bool> ka = const_truth(a, e.lhs->loc);
                bool is_and = e.bin_op == ast::BinOp::And;
                if (ka && *ka != is_and) return Value::boolean(g->constant(*ka ? 1.0f : 0.0f));
                Value b = eval(*e.rhs, env);
                NodeId tb = truth(b, e.rhs->loc);
                if (ka) return Value::boolean(tb);
                return Value::boolean(g->binary(is_and ? Op::And : Op::Or, truth(a, e.lhs->loc), tb));
            }
            Value a = eval(*e.lhs, env);
            Value b = eval(*e.rhs, env);
            return binary(e.bin_op, a, b, e.loc);
        }
        case K::Ternary: {
            Value c = eval(*e.elems[0], env);
            std::optional<bool> k = const_truth(c, e.elems[0]->loc);
            if (k) return eval(*e.elems[*k ? 1 : 2], env);
            NodeId cond = truth(c, e.elems[0]->loc);
            Value a = eval(*e.elems[1], env), b = eval(*e.elems[2], env);
            if (a.t == VT::Shape && b.t == VT::Shape && !g->depends_on_point(cond))
                return Value::of_shape(choose(cond, a.shape, b.shape, e.loc));  // on time alone
            if (!a.numeric() || a.t != b.t || a.n != b.n)
                fail(e.loc, fmt::format("a choice on the point or time needs two numbers or vectors of one size, not {} and {}",
                                        describe(a), describe(b)));
            Value r = a;
            for (int i = 0; i < a.n; ++i) r.c[i] = g->select(cond, a.c[i], b.c[i]);
            return r;
        }
        case K::If: {
            Value c = eval(*e.elems[0], env);
            std::optional<bool> k = const_truth(c, e.elems[0]->loc);
            if (!k) {
                NodeId cond = truth(c, e.elems[0]->loc);
                if (g->depends_on_point(cond)) fail(e.elems[0]->loc, "a shape cannot be chosen by a condition on the point");
                // On time alone (GLSL, where time is iTime): both branches, chosen per frame.
                ShapePtr a = to_shape(eval(*e.elems[1], env), e.elems[1]->loc, "a branch");
                ShapePtr b = e.elems.size() > 2 && e.elems[2] ? to_shape(eval(*e.elems[2], env), e.elems[2]->loc, "a branch")
                                                              : union_of({}, e.loc);
                return Value::of_shape(choose(cond, a, b, e.loc));
            }
            if (*k) return eval(*e.elems[1], env);
            if (e.elems.size() > 2 && e.elems[2]) return eval(*e.elems[2], env);
            return Value::of_shape(union_of({}, e.loc));
        }
        case K::For: {
            // for in modifier-target position: the union of the iterations.
            std::vector<ShapePtr> shapes;
            run_for(e.bindings, env, e.loc, [&](Env* body) {
                Value v = e.block ? eval_block(*e.block, body, false) : eval(*e.body, body);
                shapes.push_back(to_shape(v, e.loc, "the body of a for"));
            });
            return Value::of_shape(union_of(std::move(shapes), e.loc));
        }
        case K::Call: {
            Value callee = eval(*e.callee, env);
            return call_value(callee, e.args, env, e.loc);
        }
        case K::Index: {
            Value v = eval(*e.lhs, env);
            Value ix = eval(*e.rhs, env);
            if (v.t == VT::List && !v.list->empty()) {
                // An index that varies (the point, time, a param) picks from numbers or vectors of
                // one size, rounded and clamped as a vector's: a chain of selects.
                const NodeId in = ix.t == VT::Number ? ix.c[0] : kNoNode;
                const Value& first = v.list->front();
                const bool same = std::all_of(v.list->begin(), v.list->end(), [&](const Value& x) {
                    return (x.t == VT::Number || x.t == VT::Vector) && x.t == first.t && x.n == first.n;
                });
                if (in != kNoNode && !g->is_const(in) && same) {
                    Value r = v.list->back();
                    for (size_t i = v.list->size() - 1; i-- > 0;) {
                        const NodeId below = g->binary(Op::Lt, in, g->constant(float(i) + 0.5f));
                        for (int k = 0; k < r.n; ++k) r.c[k] = g->select(below, (*v.list)[i].c[k], r.c[k]);
                    }
                    return r;
                }
            }
            if (v.t == VT::List) {
                float i = const_num(ix, e.rhs->loc, "an index");
                if (i != std::floor(i)) fail(e.rhs->loc, fmt::format("index {} is not a whole number", i));
                if (i < 0 || i >= float(v.list->size()))
                    fail(e.rhs->loc, fmt::format("index {} is out of range for a list of {}", i, v.list->size()));
                return (*v.list)[size_t(i)];
            }
            if (v.t != VT::Vector) fail(e.lhs->loc, fmt::format("only vectors and lists can be indexed, not {}", describe(v)));
            NodeId in = num(ix, e.rhs->loc, "an index");
            if (g->is_const(in)) {
                float i = g->const_value(in);
                if (i != std::floor(i)) fail(e.rhs->loc, fmt::format("index {} is not a whole number", i));
                if (i < 0 || i >= v.n) fail(e.rhs->loc, fmt::format("index {} is out of range for {}", i, describe(v)));
                return Value::number(v.c[int(i)]);
            }
            NodeId r = v.c[v.n - 1];
            for (int i = v.n - 2; i >= 0; --i) r = g->select(g->binary(Op::Lt, in, g->constant(i + 0.5f)), v.c[i], r);
            return Value::number(r);
        }
        case K::Swizzle: {
            Value v = eval(*e.lhs, env);
            if (v.t != VT::Vector && v.t != VT::Number)
                fail(e.loc, fmt::format("'.{}' needs a vector, not {}", e.text, describe(v)));
            if (e.text.size() > 4) fail(e.loc, fmt::format("swizzle '.{}' has more than 4 components", e.text));
            NodeId c[4];
            bool xyzw = false, rgba = false;
            for (size_t i = 0; i < e.text.size(); ++i) {
                char ch = e.text[i];
                int idx = -1;
                if (const char* p = std::strchr("xyzw", ch); p && ch) { idx = int(p - "xyzw"); xyzw = true; }
                else if (const char* q = std::strchr("rgba", ch); q && ch) { idx = int(q - "rgba"); rgba = true; }
                int n = v.t == VT::Number ? 1 : v.n;
                if (idx < 0) fail(e.loc, fmt::format("'{}' is not a component name (use x y z w or r g b a)", ch));
                if (idx >= n) fail(e.loc, fmt::format("'.{}' reads component {} of {}", e.text, ch, describe(v)));
                c[i] = v.c[idx];
            }
            if (xyzw && rgba) fail(e.loc, fmt::format("'.{}' mixes xyzw and rgba letters", e.text));
            if (e.text.size() == 1) return Value::number(c[0]);
            return Value::vector(c, int(e.text.size()));
        }
        case K::Apply:
            return apply(e, env);  // (eval handles these two)
        case K::BlockExpr:
            return eval_block(*e.block, env, env->field_scope);
        case K::Field: {
            float bound = 1.0f;
            for (const auto& a : e.args) {
                if (!a.name.empty() && a.name != "bound")
                    fail(a.loc, fmt::format("unknown argument '{}' of field (did you mean `bound`?)", a.name));
                bound = const_num(eval(*a.value, env), a.value->loc, "the field's bound");
                if (!(bound > 0.0f) || !std::isfinite(bound)) fail(a.value->loc, "the field's bound must be a positive number");
            }
            if (e.args.size() > 1) fail(e.args[1].loc, "field takes one argument, bound");
            Shape s{ShapeKind::Field, e.loc};
            s.bound = bound;
            const ast::Expr* body = e.body.get();
            std::string param = e.text;
            Loc ploc = e.loc;
            pin_envs();  // the closure keeps env
            s.field = [this, env, body, param, ploc](Graph&, const Vec3N& p) -> NodeId {
                if (call_depth + 1 > opts.limits.max_recursion)
                    fail(ploc, fmt::format("recursion deeper than {} calls (raise it with --max-recursion)", opts.limits.max_recursion));
                count_calls(1, ploc);
                struct Depth {
                    int& d;
                    ~Depth() { --d; }
                } depth{++call_depth};
                const size_t mark = envs.size();
                Env* fe = new_env(env, true);
                fe->vars[param] = Binding{Value::vector(p.data(), 3), false, ploc, true};
                Value v = eval(*body, fe);
                release_envs(mark);
                if (v.t != VT::Number) fail(body->loc, fmt::format("a field must compute a number (the distance), not {}", describe(v)));
                return v.c[0];
            };
            s.field_rgb = [this, env, body, param, ploc](Graph&, const Vec3N& p) -> Vec3N {
                count_calls(1, ploc);
                const size_t mark = envs.size();
                Env* fe = new_env(env, true);
                fe->vars[param] = Binding{Value::vector(p.data(), 3), false, ploc, true};
                Value v = eval(*body, fe);
                release_envs(mark);
                if (v.t != VT::Vector || v.n != 3)
                    fail(body->loc, fmt::format("a colour field must compute [r, g, b], not {}", describe(v)));
                return {v.c[0], v.c[1], v.c[2]};
            };
            return Value::of_shape(make_shape(std::move(s)));
        }
    }
    fail(e.loc, "internal: unknown expression");
}

std::string unknown_name_message(const std::string& name, const std::vector<std::string>& names) {
    if (std::string hint = habit_hint(name); !hint.empty()) return fmt::format("unknown name '{}'{}", name, hint);
    std::vector<std::string> all = builtin_names();  // (in this order: ties go to the first)
    all.insert(all.end(), names.begin(), names.end());
    all.insert(all.end(), std::begin(kConstantNames), std::end(kConstantNames));
    const std::string near = nearest_name(name, all);
    return near.empty() ? fmt::format("unknown name '{}'", name) : fmt::format("unknown name '{}' (did you mean `{}`?)", name, near);
}

Value Interp::call_value(const Value& callee, const std::vector<ast::Arg>& args, Env* env, Loc loc) {
    if (callee.t == VT::Function) {
        if (callee.fn->builtin) return call_builtin(builtin_info(callee.fn->id), args, env, loc);
        return call_user(*callee.fn, args, env, loc);
    }
    if (callee.t == VT::Shape) {
        // A shape applied to a point gives its distance there.
        if (args.size() != 1 || !args[0].name.empty()) fail(loc, "a shape is applied to one point: s(p)");
        Value p = eval(*args[0].value, env);
        Vec3N pv = vec3(p, args[0].loc, "the point a shape is applied to", false);
        count_calls(callee.shape->tree_size, loc);
        NodeId d = lower_distance(*g, *callee.shape, pv);
        return Value::number(d);
    }
    if (callee.t == VT::Modifier && args.size() == 1 && args[0].name.empty()) {
        // `translate(v) (k > 1 ? a : b)`: the parenthesised target reads as a call.
        Value t = eval_target(*args[0].value, env, callee.mod->name);
        ShapePtr target = to_shape(t, args[0].loc, fmt::format("the target of {}", callee.mod->name).c_str());
        return Value::of_shape(apply_modifier(*callee.mod, target, loc));
    }
    fail(loc, fmt::format("{} cannot be called", describe(callee)));
}

Value Interp::call_user(const Callable& fn, const std::vector<ast::Arg>& args, Env* env, Loc loc, const Value* last) {
    const ast::Stmt& def = *fn.def;
    std::vector<const ast::Expr*> given(def.params.size(), nullptr);
    std::vector<Value> values(def.params.size());
    size_t pos = 0;
    bool named_seen = false;
    for (const auto& a : args) {
        size_t idx;
        if (a.name.empty()) {
            if (named_seen) fail(a.loc, "a positional argument cannot follow a named one");
            if (pos >= def.params.size())
                fail(a.loc, fmt::format("{} takes {} argument{}, but more were given", fn.name, def.params.size(),
                                        def.params.size() == 1 ? "" : "s"));
            idx = pos++;
        } else {
            named_seen = true;
            auto it = std::find_if(def.params.begin(), def.params.end(), [&](const ast::Param& p) { return p.name == a.name; });
            if (it == def.params.end()) {
                std::vector<std::string> names;
                for (const auto& p : def.params) names.push_back(p.name);
                std::string near = nearest_name(a.name, names);
                fail(a.loc, near.empty() ? fmt::format("{} has no parameter '{}'", fn.name, a.name)
                                         : fmt::format("{} has no parameter '{}' (did you mean `{}`?)", fn.name, a.name, near));
            }
            idx = size_t(it - def.params.begin());
            if (given[idx]) fail(a.loc, fmt::format("argument '{}' of {} is given twice", a.name, fn.name));
        }
        given[idx] = a.value.get();
        values[idx] = eval(*a.value, env);
    }
    if (call_depth + 1 > opts.limits.max_recursion)
        fail(loc, fmt::format("recursion deeper than {} calls in '{}' (raise it with --max-recursion)", opts.limits.max_recursion, fn.name));
    count_calls(1, loc);
    struct Depth {  // back out on any exit: the run goes on with the next statement after an error
        int& d;
        ~Depth() { --d; }
    } depth{++call_depth};
    const size_t mark = envs.size();
    Env* callenv = new_env(fn.env);
    callenv->field_scope = env->field_scope;
    for (size_t i = 0; i < def.params.size(); ++i) {
        const ast::Param& p = def.params[i];
        if (!given[i] && last && i + 1 == def.params.size()) {
            values[i] = *last;  // the shape a user modifier is written before
        } else if (!given[i]) {
            if (!p.default_value) fail(loc, fmt::format("missing argument '{}' of {}", p.name, fn.name));
            values[i] = eval(*p.default_value, callenv);
        }
        callenv->vars[p.name] = Binding{values[i], false, p.loc};
    }
    Value r;
    try {
        r = eval(*def.value, callenv);
    } catch (CompileError& e) {
        throw called_from(e, fn, loc);
    }
    release_envs(mark);
    return r;
}

// An error inside a def's body names the call it came from (the innermost one: the values
// the body was given), unless it is one of the whole script's limits.
CompileError Interp::called_from(const CompileError& e, const Callable& fn, Loc call) {
    std::vector<Diagnostic> d = e.diagnostics();
    if (d.empty() || !call.known()) return e;
    std::string& m = d.back().message;
    const Loc& at = d.back().loc;
    if (m.find("(raise it with --max-") != std::string::npos || m.find(", called at ") != std::string::npos ||
        (at.file == call.file && at.line == call.line && at.col == call.col))
        return e;
    m += call.file == at.file || !call.file ? fmt::format(" (in {}, called at line {})", fn.name, call.line)
                                            : fmt::format(" (in {}, called at {}:{})", fn.name, call.file->path, call.line);
    return CompileError(std::move(d));
}

// Whether a call of `fn` with `args` leaves its last parameter, one without a default, to
// the shape written after it (a user modifier: `def at(v, s) = translate(v) s;`, `at([1, 0,
// 0]) sphere(1);`, as OpenSCAD's modules take children()).
bool leaves_last_to_target(const Callable& fn, const std::vector<ast::Arg>& args) {
    const ast::Stmt& def = *fn.def;
    if (def.params.empty() || def.params.back().default_value) return false;
    size_t positional = 0;
    for (const auto& a : args) {
        if (a.name.empty()) ++positional;
        else if (a.name == def.params.back().name) return false;
    }
    return positional < def.params.size();
}

Value Interp::apply(const ast::Expr& e, Env* env) {
    Value m;
    if (e.lhs->kind == ast::ExprKind::Call) {
        const Value callee = eval(*e.lhs->callee, env);
        if (callee.t == VT::Function && !callee.fn->builtin && callee.fn->def && leaves_last_to_target(*callee.fn, e.lhs->args)) {
            const Value t = eval_target(*e.rhs, env, callee.fn->name);
            const Value target = Value::of_shape(to_shape(t, e.rhs->loc, fmt::format("the target of {}", callee.fn->name).c_str()));
            Value r = call_user(*callee.fn, e.lhs->args, env, e.lhs->loc, &target);
            if (r.t != VT::Shape)
                fail(e.lhs->loc, fmt::format("{} is written before a shape, so it must return a shape, but it returns {}", callee.fn->name, describe(r)));
            return r;
        }
        m = call_value(callee, e.lhs->args, env, e.lhs->loc);
    } else {
        m = eval(*e.lhs, env);
    }
    if (m.t == VT::Function && m.fn->builtin) {
        const BuiltinInfo& bi = builtin_info(m.fn->id);
        if (bi.kind == BuiltinKind::Modifier || bi.kind == BuiltinKind::MaterialCtor)
            m = call_builtin(bi, {}, env, e.lhs->loc);
    }
    if (m.t == VT::Material) {
        auto mv = std::make_shared<ModifierVal>();
        mv->id = Builtin::MaterialFn;
        mv->name = "material";
        mv->loc = e.lhs->loc;
        mv->material = *m.mat;
        m = Value{};
        m.t = VT::Modifier;
        m.mod = mv;
    }
    if (m.t != VT::Modifier)
        fail(e.lhs->loc, fmt::format("{} is written before a shape but is not an operation{}", describe(m),
                                     m.t == VT::Shape ? " (is a ';' missing after it?)" : ""));
    Value t = eval_target(*e.rhs, env, m.mod->name);
    ShapePtr target = to_shape(t, e.rhs->loc, fmt::format("the target of {}", m.mod->name).c_str());
    return Value::of_shape(apply_modifier(*m.mod, target, e.loc));
}

Value Interp::eval_target(const ast::Expr& target, Env* env, const std::string& op) {
    struct On {
        std::vector<std::string>& v;
        ~On() { v.pop_back(); }
    } on{targets};
    targets.push_back(op);
    return eval(target, env);
}

// A light or camera (any setting) written inside an operation's target is set as written:
// the operation applies to shapes only. A warning (once a place).
void Interp::note_setting_in_target(const BuiltinInfo& info, Loc loc) {
    if (targets.empty()) return;
    const std::string msg = fmt::format("{}(...) is inside the target of {}, which applies to shapes only: the {} is set as written, "
                                        "not moved, turned or scaled (write it outside the operation)",
                                        info.name, targets.back(), info.name);
    warn(loc, msg);
}

void Interp::warn(Loc loc, std::string message) {
    if (!warned.emplace(loc.file, loc.line, loc.col, message).second) return;
    scene.warnings.push_back({loc, std::move(message)});
}

// ---------------------------------------------------------------- operators

// A list literal's value: 2 to 4 numbers are a vector, anything else a list.
Value Interp::list_value(std::vector<Value> items, Loc loc) {
    bool all_num = true;
    for (const Value& it : items) all_num &= it.t == VT::Number;
    if (all_num && items.size() >= 2 && items.size() <= 4) {
        NodeId c[4];
        for (size_t i = 0; i < items.size(); ++i) c[i] = items[i].c[0];
        return Value::vector(c, int(items.size()));
    }
    // ([x] is a list of one number)
    check_list_size(items.size(), loc);
    Value v;
    v.t = VT::List;
    v.depth = 1;
    for (const Value& it : items) v.depth = std::max(v.depth, it.depth + 1);
    // Lists built by a loop (`l = [l];`) nest without nesting the syntax.
    if (v.depth > uint32_t(opts.limits.max_nesting))
        fail(loc, fmt::format("lists nested deeper than {} levels ({})", opts.limits.max_nesting,
                              opts.limits.max_nesting >= ast::ParseOptions::kMostNesting ? "the most --max-nesting allows"
                                                                                         : "raise it with --max-nesting"));
    v.list = std::make_shared<const std::vector<Value>>(std::move(items));
    return v;
}

Value Interp::componentwise(const Value& a, Loc loc, const std::function<NodeId(NodeId)>& f) {
    Value r = a;
    if (r.t == VT::Bool) r.t = VT::Number;
    for (int i = 0; i < a.n; ++i) r.c[i] = checked(f(a.c[i]), loc);
    return r;
}

Value Interp::componentwise2(const Value& a, const Value& b, Loc loc, const std::function<NodeId(NodeId, NodeId)>& f) {
    if (a.t == VT::Vector && b.t == VT::Vector && a.n != b.n)
        fail(loc, fmt::format("vector sizes differ: {} and {} components", a.n, b.n));
    Value r = a.t == VT::Vector ? a : b;
    if (r.t == VT::Bool) r.t = VT::Number;
    int n = std::max(a.t == VT::Vector ? a.n : 1, b.t == VT::Vector ? b.n : 1);
    r.n = uint8_t(n);
    for (int i = 0; i < n; ++i) r.c[i] = checked(f(a.c[a.t == VT::Vector ? i : 0], b.c[b.t == VT::Vector ? i : 0]), loc);
    return r;
}

Value Interp::unary(ast::UnOp op, const Value& a, Loc loc) {
    if (op == ast::UnOp::Not) {
        if (a.t == VT::Shape)
            fail(loc, "! of a shape: OpenSCAD's debug modifiers # % * ! have no use here (delete it, or comment the "
                      "statement out)");
        return Value::boolean(g->unary(Op::Not, truth(a, loc)));
    }
    if (a.t != VT::Number && a.t != VT::Vector) fail(loc, fmt::format("cannot negate {}", describe(a)));
    return componentwise(a, loc, [&](NodeId x) { return g->neg(x); });
}

Value Interp::binary(ast::BinOp op, const Value& a, const Value& b, Loc loc) {
    using B = ast::BinOp;
    auto arith_ok = [&](const Value& v) { return v.t == VT::Number || v.t == VT::Vector; };
    if (op == B::Eq || op == B::Ne) {
        if (a.t == VT::String && b.t == VT::String) {
            bool eq = *a.str == *b.str;
            return Value::boolean(g->constant((eq == (op == B::Eq)) ? 1.0f : 0.0f));
        }
        if (a.numeric() && b.numeric()) {
            if (a.n != b.n) fail(loc, fmt::format("cannot compare {} with {}", describe(a), describe(b)));
            NodeId r = g->constant(op == B::Eq ? 1.0f : 0.0f);
            for (int i = 0; i < a.n; ++i) {
                NodeId c = g->binary(op == B::Eq ? Op::Eq : Op::Ne, a.c[i], b.c[i]);
                r = i == 0 ? c : g->binary(op == B::Eq ? Op::And : Op::Or, r, c);
            }
            return Value::boolean(r);
        }
        fail(loc, fmt::format("cannot compare {} with {}", describe(a), describe(b)));
    }
    if (op == B::Lt || op == B::Le || op == B::Gt || op == B::Ge) {
        if (a.t != VT::Number || b.t != VT::Number)
            fail(loc, fmt::format("'{}' compares numbers, not {} and {}", op == B::Lt ? "<" : op == B::Le ? "<=" : op == B::Gt ? ">" : ">=",
                                  describe(a), describe(b)));
        NodeId x = a.c[0], y = b.c[0];
        switch (op) {
            case B::Lt: return Value::boolean(g->binary(Op::Lt, x, y));
            case B::Le: return Value::boolean(g->binary(Op::Le, x, y));
            case B::Gt: return Value::boolean(g->binary(Op::Lt, y, x));
            default: return Value::boolean(g->binary(Op::Le, y, x));
        }
    }
    if (!arith_ok(a) || !arith_ok(b)) {
        const char* sym = op == B::Add ? "+" : op == B::Sub ? "-" : op == B::Mul ? "*" : op == B::Div ? "/" : "%";
        // `translate(v) %sphere(1)`, `rotate(a) *box(1)`: OpenSCAD's debug modifiers after a modifier.
        const bool debug = (op == B::Mod || op == B::Mul) && b.t == VT::Shape;
        fail(loc, fmt::format("cannot apply '{}' to {} and {}{}", sym, describe(a), describe(b),
                              debug ? " (OpenSCAD's debug modifiers # % * ! have no use here: delete it)" : ""));
    }
    Op o = op == B::Add ? Op::Add : op == B::Sub ? Op::Sub : op == B::Mul ? Op::Mul : op == B::Div ? Op::Div : Op::Mod;
    return componentwise2(a, b, loc, [&](NodeId x, NodeId y) {
        if ((o == Op::Div || o == Op::Mod) && g->is_const(y) && g->const_value(y) == 0.0f)
            fail(loc, o == Op::Div ? "division by zero" : "modulo by zero");
        return g->binary(o, x, y);
    });
}

}  // namespace sdfc
