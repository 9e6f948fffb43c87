// Statements and expressions. Builtins (shapes, operations, settings, math) are in builtins.cpp.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>

#include <fmt/format.h>

#include "compiler/scene/lower.hpp"
#include "lang/interp.hpp"

namespace sdfc {

const char* type_name(VT t) {
    switch (t) {
        case VT::None: return "nothing";
        case VT::Number: return "number";
        case VT::Bool: return "bool";
        case VT::Vector: return "vector";
        case VT::List: return "list";
        case VT::Range: return "range";
        case VT::String: return "string";
        case VT::Material: return "material";
        case VT::Shape: return "shape";
        case VT::Function: return "function";
        case VT::Modifier: return "operation";
    }
    return "?";
}

Interp::Interp(SourceManager& s, const InterpretOptions& o) : sm(s), opts(o), g(std::make_shared<Graph>()) {
    g->set_node_limit(opts.limits.max_ops);
}

Env* Interp::new_env(Env* parent, bool field_scope) {
    envs.push_back(std::make_unique<Env>());
    Env* e = envs.back().get();
    e->parent = parent;
    e->field_scope = field_scope || (parent && parent->field_scope);
    return e;
}

void Interp::fail(Loc loc, std::string msg) { throw CompileError(loc, std::move(msg)); }

std::string Interp::describe(const Value& v) {
    if (v.t == VT::Vector) return fmt::format("a {}-component vector", v.n);
    if (v.t == VT::None) return "nothing";
    std::string n = type_name(v.t);
    bool vowel = n[0] == 'a' || n[0] == 'o';
    return (vowel ? "an " : "a ") + n;
}

NodeId Interp::checked(NodeId n, Loc loc) {
    if (g->is_const(n) && !std::isfinite(g->const_value(n)))
        fail(loc, fmt::format("this expression is not a finite number ({})", g->const_value(n)));
    return n;
}

NodeId Interp::num(const Value& v, Loc loc, const char* what) {
    if (v.t == VT::Number || v.t == VT::Bool) return v.c[0];
    fail(loc, fmt::format("{} must be a number, not {}", what, describe(v)));
}

float Interp::const_num(const Value& v, Loc loc, const char* what) {
    NodeId n = num(v, loc, what);
    if (!g->is_const(n)) fail(loc, fmt::format("{} must be known when the script runs (it depends on the point or on time)", what));
    return g->const_value(n);
}

Vec3N Interp::vec3(const Value& v, Loc loc, const char* what, bool broadcast) {
    if (v.t == VT::Vector && v.n == 3) return {v.c[0], v.c[1], v.c[2]};
    if (broadcast && v.t == VT::Number) return {v.c[0], v.c[0], v.c[0]};
    fail(loc, fmt::format("{} must be a 3-component vector{}, not {}", what, broadcast ? " or a number" : "", describe(v)));
}

NodeId Interp::truth(const Value& v, Loc loc) {
    if (v.t == VT::Bool) return v.c[0];
    if (v.t == VT::Number) return g->binary(Op::Ne, v.c[0], g->constant(0));
    fail(loc, fmt::format("a condition must be a bool or a number, not {}", describe(v)));
}

std::optional<bool> Interp::const_truth(const Value& v, Loc loc) {
    NodeId t = truth(v, loc);
    if (!g->is_const(t)) return std::nullopt;
    return g->const_value(t) != 0.0f;
}

void Interp::check_limit_iterations(long n, Loc loc) {
    total_iterations += n;
    if (total_iterations > opts.limits.max_total_iterations)
        fail(loc, fmt::format("loops ran more than {} iterations in all (raise it with --max-iterations)",
                              opts.limits.max_total_iterations));
}

void Interp::count_calls(size_t n, Loc loc) {
    total_calls += n;
    if (total_calls > opts.limits.max_calls)
        fail(loc, fmt::format("the script made more than {} calls in all, counting field bodies and shapes applied "
                              "to points (raise it with --max-calls)",
                              opts.limits.max_calls));
}

ShapePtr Interp::make_shape(Shape s) {
    if (++shape_count > opts.limits.max_shapes)
        fail(s.loc, fmt::format("the scene has more than {} shapes (raise it with --max-shapes)", opts.limits.max_shapes));
    for (const auto& c : s.children) {
        s.depth = std::max(s.depth, c->depth + 1);
        s.tree_size += std::min(c->tree_size, opts.limits.max_shapes + 1);
    }
    // A shape used twice is lowered twice: count the tree as lowering walks it, so that
    // sharing (`let b = union { a; a; }; let c = union { b; b; }; ...`) cannot blow up.
    if (s.tree_size > opts.limits.max_shapes)
        fail(s.loc, fmt::format("the scene has more than {} shapes, counting a shared shape at each use "
                                "(raise it with --max-shapes)",
                                opts.limits.max_shapes));
    if (s.depth > opts.limits.max_shape_depth)
        fail(s.loc, fmt::format("shapes nested more than {} deep (raise it with --max-shape-depth)", opts.limits.max_shape_depth));
    return std::make_shared<const Shape>(std::move(s));
}

ShapePtr Interp::union_of(std::vector<ShapePtr> shapes, Loc loc) {
    if (shapes.size() == 1) return shapes[0];
    Shape s{ShapeKind::Union, loc};
    if (shapes.empty()) s.kind = ShapeKind::Empty;
    s.children = std::move(shapes);
    return make_shape(std::move(s));
}

ShapePtr Interp::choose(NodeId cond, ShapePtr a, ShapePtr b, Loc loc) {
    Shape s{ShapeKind::Choose, loc};
    s.params = {cond};
    s.children = {std::move(a), std::move(b)};
    return make_shape(std::move(s));
}

ShapePtr Interp::to_shape(const Value& v, Loc loc, const char* what) {
    if (v.t == VT::Shape) return v.shape;
    if (v.t == VT::None) return union_of({}, loc);
    if (v.t == VT::Modifier) fail(loc, fmt::format("{} needs a shape to apply to", v.mod->name));
    fail(loc, fmt::format("{} must be a shape, not {}", what, describe(v)));
}

// ---------------------------------------------------------------- running a file

Scene Interp::run(const SourceFile& file) {
    scene.graph = g;
    set_default_settings(scene);
    scene.time = opts.time.value_or(0.0f);

    modules.push_back(ast::parse(file, ast::ParseOptions{opts.limits.max_nesting}));
    const ast::Module& m = *modules.back();
    Env* top = new_env(nullptr);
    import_stack.push_back(std::filesystem::weakly_canonical(file.path).string());
    std::vector<ShapePtr> shapes;
    std::vector<Diagnostic> errors;
    // Defs first, so a def may be used above the line that defines it.
    for (const auto& st : m.stmts)
        if (st->kind == ast::StmtKind::Def) {
            try {
                exec(*st, top, shapes);
            } catch (const CompileError& e) {
                errors.insert(errors.end(), e.diagnostics().begin(), e.diagnostics().end());
            }
        }
    for (const auto& st : m.stmts) {
        if (st->kind == ast::StmtKind::Def) continue;
        try {
            exec(*st, top, shapes);
        } catch (const CompileError& e) {
            errors.insert(errors.end(), e.diagnostics().begin(), e.diagnostics().end());
            if (errors.size() >= 20) break;
        }
    }
    if (!errors.empty()) throw CompileError(std::move(errors));
    scene.root = union_of(std::move(shapes), Loc{&file, 1, 1});
    return scene;
}

// ---------------------------------------------------------------- statements

void Interp::exec_stmts(const std::vector<ast::StmtPtr>& stmts, Env* env, std::vector<ShapePtr>& out) {
    for (const auto& st : stmts)
        if (st->kind == ast::StmtKind::Def) exec(*st, env, out);
    for (const auto& st : stmts)
        if (st->kind != ast::StmtKind::Def) exec(*st, env, out);
}

namespace {
struct IterItem {
    Value v;
};
}  // namespace

void Interp::exec(const ast::Stmt& s, Env* env, std::vector<ShapePtr>& out) {
    check_stack(s.loc);
    g->set_loc(s.loc);
    switch (s.kind) {
        case ast::StmtKind::Empty:
            return;
        case ast::StmtKind::Let:
        case ast::StmtKind::Var: {
            if (s.kind == ast::StmtKind::Var && !env->field_scope)
                fail(s.loc, "'var' is only allowed inside a field block; use 'let' for a constant");
            // Built-in functions keep their names; the constants (pi, tau, e, time) may be shadowed.
            if (find_builtin(s.name))
                fail(s.name_loc, fmt::format("'{}' is a built-in name and cannot be redefined", s.name));
            auto it = env->vars.find(s.name);
            if (it != env->vars.end())
                fail(s.name_loc, fmt::format("'{}' is already defined in this scope (at line {})", s.name, it->second.loc.line));
            Value v = eval(*s.value, env);
            env->vars[s.name] = Binding{std::move(v), s.kind == ast::StmtKind::Var, s.name_loc};
            return;
        }
        case ast::StmtKind::Assign: {
            Binding* b = env->find(s.name);
            if (!b) fail(s.name_loc, fmt::format("unknown variable '{}'", s.name));
            if (!b->mut) fail(s.name_loc, fmt::format("'{}' is a constant (declared with let at line {}); declare it with var to reassign it", s.name, b->loc.line));
            Value v = eval(*s.value, env);
            if (v.t != b->value.t || v.n != b->value.n)
                fail(s.value->loc, fmt::format("'{}' holds {}; it cannot be assigned {}", s.name, describe(b->value), describe(v)));
            b->value = std::move(v);
            return;
        }
        case ast::StmtKind::Def: {
            if (find_builtin(s.name))
                fail(s.name_loc, fmt::format("'{}' is a built-in name and cannot be redefined", s.name));
            auto it = env->vars.find(s.name);
            if (it != env->vars.end())
                fail(s.name_loc, fmt::format("'{}' is already defined in this scope (at line {})", s.name, it->second.loc.line));
            for (size_t i = 0; i < s.params.size(); ++i)
                for (size_t j = 0; j < i; ++j)
                    if (s.params[i].name == s.params[j].name)
                        fail(s.params[i].loc, fmt::format("parameter '{}' is named twice in '{}'", s.params[i].name, s.name));
            auto fn = std::make_shared<Callable>();
            fn->name = s.name;
            fn->def = &s;
            fn->env = env;
            pin_envs();
            Value v;
            v.t = VT::Function;
            v.fn = fn;
            env->vars[s.name] = Binding{std::move(v), false, s.name_loc};
            return;
        }
        case ast::StmtKind::Import: {
            namespace fs = std::filesystem;
            fs::path base = fs::path(s.loc.file->path).parent_path();
            fs::path target = (base / s.name).lexically_normal();  // as diagnostics show it
            std::string key = fs::weakly_canonical(target).string();
            if (std::find(import_stack.begin(), import_stack.end(), key) != import_stack.end()) {
                std::string chain;
                for (const auto& p : import_stack) chain += fs::path(p).filename().string() + " -> ";
                fail(s.loc, fmt::format("import cycle: {}{}", chain, target.filename().string()));
            }
            Env* defs = nullptr;
            auto found = imported.find(key);
            if (found != imported.end()) {
                defs = found->second;
            } else {
                const SourceFile& f = sm.load(target.string(), s.loc, opts.limits.max_file_bytes);
                // Registered before it runs: each file is read once, and an error in it is
                // reported once (a later import gets what was defined before the error).
                defs = new_env(nullptr);
                imported[key] = defs;
                pin_envs();
                modules.push_back(ast::parse(f, ast::ParseOptions{opts.limits.max_nesting}));
                const ast::Module& m = *modules.back();
                import_stack.push_back(key);
                struct Pop {  // also when the import fails: the run goes on with the next statement
                    std::vector<std::string>& stack;
                    ~Pop() { stack.pop_back(); }
                } pop{import_stack};
                std::vector<ShapePtr> ignored;
                // Only definitions travel: defs and lets (and the imports they need).
                for (const auto& st : m.stmts)
                    if (st->kind == ast::StmtKind::Def) exec(*st, defs, ignored);
                for (const auto& st : m.stmts)
                    if (st->kind == ast::StmtKind::Let || st->kind == ast::StmtKind::Import) exec(*st, defs, ignored);
            }
            for (const auto& [name, b] : defs->vars)
                if (!env->vars.count(name)) env->vars[name] = b;
            return;
        }
        case ast::StmtKind::Expr: {
            Value v = eval(*s.value, env);
            if (v.t == VT::Shape) {
                out.push_back(v.shape);
            } else if (v.t == VT::None) {
                // settings statements
            } else if (v.t == VT::Modifier) {
                fail(s.value->loc, fmt::format("'{}' needs a shape to apply to, e.g. {}(...) sphere(1);", v.mod->name, v.mod->name));
            } else {
                fail(s.value->loc, fmt::format("this statement computes {} but does nothing with it (a statement must be a shape or a setting)", describe(v)));
            }
            return;
        }
        case ast::StmtKind::If: {
            Value c = eval(*s.value, env);
            std::optional<bool> k = const_truth(c, s.value->loc);
            if (k) {
                const ast::Stmt* branch = *k ? s.then_branch.get() : s.else_branch.get();
                if (branch) {
                    Env* inner = new_env(env);
                    exec(*branch, inner, out);
                }
                return;
            }
            // A condition on the point or time: run both branches and merge the variables
            // they assign with a select. Shapes cannot be chosen per point.
            NodeId cond = truth(c, s.value->loc);
            std::vector<std::pair<Binding*, Value>> saved;
            for (Env* e = env; e; e = e->parent)
                for (auto& [name, b] : e->vars)
                    if (b.mut) saved.emplace_back(&b, b.value);
            std::vector<ShapePtr> then_shapes, else_shapes;
            auto run_branch = [&](const ast::Stmt* br, std::vector<ShapePtr>& shapes) {
                std::vector<Value> result;
                if (br) {
                    Env* inner = new_env(env);
                    exec(*br, inner, shapes);
                }
                for (auto& [b, v] : saved) result.push_back(b->value);
                for (auto& [b, v] : saved) b->value = v;
                return result;
            };
            std::vector<Value> then_vals = run_branch(s.then_branch.get(), then_shapes);
            std::vector<Value> else_vals = run_branch(s.else_branch.get(), else_shapes);
            if (!then_shapes.empty() || !else_shapes.empty()) {
                if (g->depends_on_point(cond))
                    fail(s.value->loc, "a shape statement cannot depend on a condition on the point; use a field or min/max");
                // On time alone (GLSL, where time is iTime): both branches, chosen per frame.
                out.push_back(choose(cond, union_of(std::move(then_shapes), s.loc), union_of(std::move(else_shapes), s.loc), s.loc));
            }
            for (size_t i = 0; i < saved.size(); ++i) {
                const Value& a = then_vals[i];
                const Value& b = else_vals[i];
                Value m = a;
                for (int j = 0; j < a.n; ++j) m.c[j] = g->select(cond, a.c[j], b.c[j]);
                if (!a.numeric() && (a.shape != b.shape || a.mat != b.mat))
                    fail(s.value->loc, "only numbers and vectors can be assigned under a condition on the point or time");
                saved[i].first->value = m;
            }
            return;
        }
        case ast::StmtKind::For: {
            // The statement adds one shape, the union of its iterations, so that it is one
            // operand of a difference or an intersection (as in OpenSCAD).
            std::vector<ShapePtr> iters;
            run_for(s.bindings, env, s.loc, [&](Env* body) { exec(*s.body, body, iters); });
            if (iters.size() <= 1) {
                out.insert(out.end(), iters.begin(), iters.end());
                return;
            }
            Shape u{ShapeKind::Union, s.loc};
            u.children = std::move(iters);
            u.iterations = true;
            out.push_back(make_shape(std::move(u)));
            return;
        }
    }
}

void Interp::run_for(const std::vector<ast::ForBinding>& bindings, Env* env, Loc loc, const std::function<void(Env*)>& body) {
    // Nested bindings: the first varies slowest.
    long count = 0;
    std::function<void(size_t, Env*)> loop = [&](size_t k, Env* outer) {
        if (k == bindings.size()) {
            if (++count > opts.limits.max_loop_iterations)
                fail(loc, fmt::format("this loop runs more than {} iterations (raise it with --max-iterations)",
                                      opts.limits.max_loop_iterations));
            check_limit_iterations(1, loc);
            body(new_env(outer));
            return;
        }
        const ast::ForBinding& b = bindings[k];
        Value it = eval(*b.iterable, outer);
        auto bind = [&](Value v) {
            const size_t mark = envs.size();
            Env* e = new_env(outer);
            e->vars[b.name] = Binding{std::move(v), false, b.loc};
            loop(k + 1, e);
            release_envs(mark);
        };
        if (it.t == VT::Range) {
            const RangeVal& r = it.range;
            double n = std::max(0.0, std::floor((double(r.end) - r.start) / r.step + 1e-6) + 1);
            if (n > double(opts.limits.max_loop_iterations))
                fail(b.iterable->loc, fmt::format("this range has {} elements, over the loop limit of {} (raise it with --max-iterations)",
                                                  n, opts.limits.max_loop_iterations));
            for (long i = 0; i < long(n); ++i) bind(Value::number(g->constant(float(r.start + double(r.step) * i))));
        } else if (it.t == VT::Vector) {
            for (int i = 0; i < it.n; ++i) bind(Value::number(it.c[i]));
        } else if (it.t == VT::List) {
            for (const Value& v : *it.list) bind(v);
        } else {
            fail(b.iterable->loc, fmt::format("for iterates over a range or a vector, not {}", describe(it)));
        }
    };
    loop(0, env);
}

// ---------------------------------------------------------------- expressions

Value Interp::eval_block(const ast::Block& b, Env* env, bool field_scope) {
    Env* inner = new_env(env, field_scope);
    std::vector<ShapePtr> shapes;
    exec_stmts(b.stmts, inner, shapes);
    if (b.result) {
        Value r = eval(*b.result, inner);
        if (r.t != VT::Shape) {
            if (!shapes.empty())
                fail(b.result->loc, fmt::format("this block adds shapes and ends with {}; a block is either a union of shapes or a value", describe(r)));
            return r;
        }
        shapes.push_back(r.shape);
    }
    // A block that adds nothing (a loop body of assignments in a field) has no value; where
    // a shape is needed, to_shape takes it as the empty shape.
    if (shapes.empty()) return Value{};
    return Value::of_shape(union_of(std::move(shapes), b.loc));
}

Value Interp::eval(const ast::Expr& e, Env* env) {
    using K = ast::ExprKind;
    check_stack(e.loc);
    g->set_loc(e.loc);
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
            if (e.text == "time") return Value::number(opts.time ? g->constant(*opts.time) : g->input(Op::Time));
            if (e.text == "pi") return Value::number(g->constant(3.14159265358979f));
            if (e.text == "tau") return Value::number(g->constant(6.28318530717959f));
            if (e.text == "e") return Value::number(g->constant(2.71828182845905f));
            if (const BuiltinInfo* bi = find_builtin(e.text)) {
                Value v;
                v.t = VT::Function;
                auto fn = std::make_shared<Callable>();
                fn->name = bi->name;
                fn->builtin = true;
                fn->id = bi->id;
                v.fn = fn;
                return v;
            }
            std::vector<std::string> names = builtin_names();
            for (Env* s = env; s; s = s->parent)
                for (const auto& [n, b] : s->vars) names.push_back(n);
            names.insert(names.end(), {"time", "pi", "tau", "e"});
            std::string near = nearest_name(e.text, names);
            fail(e.loc, near.empty() ? fmt::format("unknown name '{}'", e.text)
                                     : fmt::format("unknown name '{}' (did you mean `{}`?)", e.text, near));
        }
        case K::Vector: {
            std::vector<Value> items;
            bool all_num = true;
            for (const auto& el : e.elems) {
                items.push_back(eval(*el, env));
                all_num &= items.back().t == VT::Number;
            }
            if (all_num && items.size() >= 2 && items.size() <= 4) {
                NodeId c[4];
                for (size_t i = 0; i < items.size(); ++i) c[i] = items[i].c[0];
                return Value::vector(c, int(items.size()));
            }
            if (all_num && items.size() == 1) {
                // [x] is a list of one number
            }
            Value v;
            v.t = VT::List;
            v.depth = 1;
            for (const Value& it : items) v.depth = std::max(v.depth, it.depth + 1);
            // Lists built by a loop (`l = [l];`) nest without nesting the syntax.
            if (v.depth > uint32_t(opts.limits.max_nesting))
                fail(e.loc, fmt::format("lists nested deeper than {} levels (raise it with --max-nesting)", opts.limits.max_nesting));
            v.list = std::make_shared<const std::vector<Value>>(std::move(items));
            return v;
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
            return apply(e, env);
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
                fe->vars[param] = Binding{Value::vector(p.data(), 3), false, ploc};
                Value v = eval(*body, fe);
                release_envs(mark);
                if (v.t != VT::Number) fail(body->loc, fmt::format("a field must compute a number (the distance), not {}", describe(v)));
                return v.c[0];
            };
            return Value::of_shape(make_shape(std::move(s)));
        }
    }
    fail(e.loc, "internal: unknown expression");
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
    fail(loc, fmt::format("{} cannot be called", describe(callee)));
}

Value Interp::call_user(const Callable& fn, const std::vector<ast::Arg>& args, Env* env, Loc loc) {
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
        if (!given[i]) {
            if (!p.default_value) fail(loc, fmt::format("missing argument '{}' of {}", p.name, fn.name));
            values[i] = eval(*p.default_value, callenv);
        }
        callenv->vars[p.name] = Binding{values[i], false, p.loc};
    }
    Value r = eval(*def.value, callenv);
    release_envs(mark);
    return r;
}

Value Interp::apply(const ast::Expr& e, Env* env) {
    Value m = eval(*e.lhs, env);
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
    Value t = eval(*e.rhs, env);
    ShapePtr target = to_shape(t, e.rhs->loc, fmt::format("the target of {}", m.mod->name).c_str());
    return Value::of_shape(apply_modifier(*m.mod, target, e.loc));
}

// ---------------------------------------------------------------- operators

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
        fail(loc, fmt::format("cannot apply '{}' to {} and {}", sym, describe(a), describe(b)));
    }
    Op o = op == B::Add ? Op::Add : op == B::Sub ? Op::Sub : op == B::Mul ? Op::Mul : op == B::Div ? Op::Div : Op::Mod;
    return componentwise2(a, b, loc, [&](NodeId x, NodeId y) {
        if ((o == Op::Div || o == Op::Mod) && g->is_const(y) && g->const_value(y) == 0.0f)
            fail(loc, o == Op::Div ? "division by zero" : "modulo by zero");
        return g->binary(o, x, y);
    });
}

// ---------------------------------------------------------------- entry points

Scene interpret_source(SourceManager& sm, const SourceFile& file, const InterpretOptions& opts) {
    auto in = std::make_shared<Interp>(sm, opts);
    Scene s = in->run(file);
    s.keepalive = in;  // field closures call back into the interpreter at compile time
    return s;
}

Scene interpret_file(SourceManager& sm, const std::string& path, const InterpretOptions& opts) {
    const SourceFile& f = sm.load(path, Loc{}, opts.limits.max_file_bytes);
    return interpret_source(sm, f, opts);
}

}  // namespace sdfc
