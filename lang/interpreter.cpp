// Statements and blocks: running a file, scopes, loops, imports. Expressions, calls and
// operators are in expressions.cpp; builtins (shapes, operations, settings, math) in builtins.cpp.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>

#include <fmt/format.h>

#include "compiler/scene/lower.hpp"
#include "compiler/base/names.hpp"
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
    if (v.t == VT::List && v.list) return fmt::format("a list of {}", v.list->size());
    std::string n = type_name(v.t);
    bool vowel = n[0] == 'a' || n[0] == 'o';
    return (vowel ? "an " : "a ") + n;
}

NodeId Interp::checked(NodeId n, Loc loc) {
    if (g->is_const(n) && !std::isfinite(g->const_value(n)))
        fail(loc, fmt::format("this expression is not a finite number ({})", shown_number(g->const_value(n))));
    return n;
}

NodeId Interp::num(const Value& v, Loc loc, const char* what) {
    if (v.t == VT::Number || v.t == VT::Bool) return v.c[0];
    fail(loc, fmt::format("{} must be a number, not {}", what, describe(v)));
}

float Interp::const_num(const Value& v, Loc loc, const char* what) {
    NodeId n = num(v, loc, what);
    if (!g->is_const(n)) fail(loc, fmt::format("{} must be known when the script runs (it depends on the point, on time or on a param)", what));
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

void Interp::check_list_size(size_t n, Loc loc) {
    if (n > opts.limits.max_list)
        fail(loc, fmt::format("a list of more than {} elements (raise it with --max-list)", opts.limits.max_list));
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
        fail(s.loc, fmt::format("the scene has more than {} shape{} (raise it with --max-shapes)", opts.limits.max_shapes,
                                opts.limits.max_shapes == 1 ? "" : "s"));
    for (const auto& c : s.children) {
        s.depth = std::max(s.depth, c->depth + 1);
        s.tree_size += std::min(c->tree_size, opts.limits.max_shapes + 1);
    }
    // A shape used twice is lowered twice: count the tree as lowering walks it, so that
    // sharing (`let b = union { a; a; }; let c = union { b; b; }; ...`) cannot blow up.
    if (s.tree_size > opts.limits.max_shapes)
        fail(s.loc, fmt::format("the scene has more than {} shape{}, counting a shared shape at each use "
                                "(raise it with --max-shapes)",
                                opts.limits.max_shapes, opts.limits.max_shapes == 1 ? "" : "s"));
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
    main_env = top;
    define_used.assign(opts.defines.size(), false);
    std::error_code ec;  // the file was read, so only a race fails here; its own path stands in
    auto key = std::filesystem::weakly_canonical(file.path, ec);
    import_stack.push_back(ec ? file.path : key.string());
    std::vector<ShapePtr> shapes;
    std::vector<Diagnostic> errors;
    // Defs first, so a def may be used above the line that defines it.
    for (const auto& st : m.stmts)
        if (st->kind == ast::StmtKind::Def) {
            try {
                exec(*st, top, shapes);
            } catch (const CompileError& e) {
                errors.insert(errors.end(), e.diagnostics().begin(), e.diagnostics().end());
                if (!top->vars.count(st->name)) failed_lets.insert(st->name);
            }
        }
    for (const auto& st : m.stmts) {
        if (st->kind == ast::StmtKind::Def) continue;
        try {
            exec(*st, top, shapes);
        } catch (const CompileError& e) {
            errors.insert(errors.end(), e.diagnostics().begin(), e.diagnostics().end());
            const bool names = st->kind == ast::StmtKind::Let || st->kind == ast::StmtKind::Var || st->kind == ast::StmtKind::Assign;
            if (names && !top->vars.count(st->name)) failed_lets.insert(st->name);
            failed_import |= st->kind == ast::StmtKind::Import;
            if (errors.size() >= 20) break;
            // A limit is the whole script's: the statements after would each repeat it.
            if (!e.diagnostics().empty() && e.diagnostics().back().message.find("(raise it with --max-") != std::string::npos) break;
        }
    }
    if (!errors.empty()) throw CompileError(std::move(errors));
    check_defines_used(top);
    warn_unknown_names(modules, scene.warnings);
    // Nothing drawn while a top-level let holds a shape: likely `let m = material(...)` with
    // its ';' missing, which took the next line's shape as its target.
    if (shapes.empty())
        for (const auto& st : m.stmts)
            if (st->kind == ast::StmtKind::Let) {
                auto it = top->vars.find(st->name);
                if (it != top->vars.end() && it->second.value.t == VT::Shape) {
                    warn(st->name_loc, fmt::format("the scene has no shapes, but '{}' holds one: write `{};` to add it (or is the "
                                                   "';' at the end of this let missing?)", st->name, st->name));
                    break;
                }
            }
    scene.root = union_of(std::move(shapes), Loc{&file, 1, 1});
    return scene;
}

// The -D value for the main script's `let`, parsed and evaluated where the let is, and of
// the same kind as the script's own value.
Value Interp::defined_value(size_t k, const ast::Stmt& let, Env* env) {
    const Define& d = opts.defines[k];
    define_used[k] = true;
    const std::string what = fmt::format("-D {}={}", d.name, d.value);
    try {
        const SourceFile& f = sm.add("-D " + d.name, d.value + ";");
        modules.push_back(ast::parse(f, ast::ParseOptions{opts.limits.max_nesting}));
        const ast::Module& m = *modules.back();
        if (m.stmts.size() != 1 || m.stmts[0]->kind != ast::StmtKind::Expr || !m.stmts[0]->value)
            throw DefineError(fmt::format("{}: the value must be one expression", what));
        Value v = eval(*m.stmts[0]->value, env);
        // The script's own value, for its kind: a param(...) in it is checked, not made; but in
        // a shader a let that is a param keeps its slider, which starts at -D's value.
        const ast::Expr& e = *let.value;
        const bool slider = !opts.time && e.kind == ast::ExprKind::Call && e.callee && e.callee->kind == ast::ExprKind::Ident &&
                            e.callee->text == "param" && v.t == VT::Number && g->is_const(v.c[0]);
        const std::string outer = param_let;
        param_let = let.name;
        params_in_let = 0;
        param_fixed = !slider;
        if (slider) param_start = g->const_value(v.c[0]);
        Value own;
        try {
            own = eval(e, env);
        } catch (...) {
            param_let = outer;
            param_fixed = false;
            param_start.reset();
            throw;
        }
        param_let = outer;
        param_fixed = false;
        param_start.reset();
        if (v.t != own.t || v.n != own.n)
            throw DefineError(fmt::format("{}: the script's '{}' (line {}) is {}, not {}", what, d.name, let.name_loc.line, describe(own),
                                          describe(v)));
        return slider && params_in_let == 1 ? own : v;  // (a script's own def named param makes none)
    } catch (const CompileError& e) {
        const auto& diags = e.diagnostics();
        std::string msg = diags.empty() ? std::string("not a value") : diags.front().message;
        // A bare word taken for a name where the script's let is a string: the shell ate
        // the quotes.
        const bool word = let.value && let.value->kind == ast::ExprKind::String && !d.value.empty() && std::all_of(d.value.begin(), d.value.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '#';
        });
        if (word && msg.rfind("unknown name", 0) == 0 && msg.find('(') == std::string::npos) msg += fmt::format(" (a string is quoted for the shell: -D '{}=\"{}\"')", d.name, d.value);
        throw DefineError(fmt::format("{}: {}", what, msg));
    }
}

void Interp::check_defines_used(Env* top) {
    for (size_t k = 0; k < opts.defines.size(); ++k) {
        if (define_used[k]) continue;
        std::vector<std::string> names;
        for (const auto& [name, b] : top->vars)
            if (b.value.t != VT::Function) names.push_back(name);
        const std::string& n = opts.defines[k].name;
        if (std::find(names.begin(), names.end(), n) != names.end())
            throw DefineError(fmt::format("-D {}: '{}' is an imported file's let; -D sets the main script's own top-level lets", n, n));
        const std::string near = nearest_name(n, names);
        throw DefineError(near.empty() ? fmt::format("-D {}: the script has no top-level `let {}`", n, n)
                                       : fmt::format("-D {}: the script has no top-level `let {}` (did you mean `{}`?)", n, n, near));
    }
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

// Whether the statement may add shapes (a shape call, a block, if or for holding one; not
// a setting, an assignment or a definition): such an `if` or `for` is one CSG operand even
// when it adds nothing (a false condition, no iterations), as in OpenSCAD, so that
// `difference { for (i = [1 : n]) ...; sphere(1); }` with n = 0 is empty, not the sphere.
bool may_add_shapes(const ast::Stmt& s) {
    switch (s.kind) {
        case ast::StmtKind::Expr: {
            const ast::Expr& e = *s.value;
            if (e.kind == ast::ExprKind::BlockExpr)
                return e.block->result || std::any_of(e.block->stmts.begin(), e.block->stmts.end(), [](const ast::StmtPtr& x) { return may_add_shapes(*x); });
            if (e.kind == ast::ExprKind::Call && e.callee && e.callee->kind == ast::ExprKind::Ident) {
                const BuiltinInfo* b = find_builtin(e.callee->text);
                return !b || b->kind != BuiltinKind::Setting;
            }
            return true;
        }
        case ast::StmtKind::If:
            return (s.then_branch && may_add_shapes(*s.then_branch)) || (s.else_branch && may_add_shapes(*s.else_branch));
        case ast::StmtKind::For:
            return s.body && may_add_shapes(*s.body);
        default:
            return false;
    }
}

// Where an earlier definition is, for a message about a later one at `here`: its line, and
// its file when that is another (an imported name).
std::string where_defined(const Loc& earlier, const Loc& here) {
    if (earlier.file == here.file || !earlier.file) return fmt::format("at line {}", earlier.line);
    return fmt::format("at {}:{}", earlier.file->path, earlier.line);
}
}  // namespace

void Interp::exec(const ast::Stmt& s, Env* env, std::vector<ShapePtr>& out) {
    check_stack(s.loc);
    g->set_loc(s.loc);
    if (s.kind == ast::StmtKind::Expr) {
        Value v = eval(*s.value, env);
        if (v.t == VT::Shape) {
            out.push_back(v.shape);
            return;
        }
        if (v.t == VT::None) return;  // settings statements
        bad_statement(s, v);
    }
    exec_rest(s, env, out);
}

[[gnu::noinline]] void Interp::bad_statement(const ast::Stmt& s, const Value& v) {
    if (v.t == VT::Modifier)
        fail(s.value->loc, fmt::format("'{}' needs a shape to apply to, e.g. {}(...) sphere(1);", v.mod->name, v.mod->name));
    fail(s.value->loc, fmt::format("this statement computes {} but does nothing with it (a statement must be a shape or a setting)", describe(v)));
}

// A def is only evaluated when called: its body's chain of modifiers is checked here, so
// that `def ring(r) = torus(r, 0.1)` with its ';' missing (the next line's shape became a
// target) is an error even if ring is never called.
void Interp::check_shape_before_shape(const ast::Expr& e) {
    for (const ast::Expr* x = &e; x && x->kind == ast::ExprKind::Apply; x = x->rhs.get()) {
        const ast::Expr* lhs = x->lhs.get();
        const ast::Expr* name = lhs && lhs->kind == ast::ExprKind::Call ? lhs->callee.get() : lhs;
        if (!name || name->kind != ast::ExprKind::Ident) continue;
        const BuiltinInfo* b = find_builtin(name->text);
        if (b && b->kind == BuiltinKind::Shape && !redefinable_builtin(name->text))
            fail(lhs->loc, "a shape is written before a shape but is not an operation (is a ';' missing after it?)");
    }
}

[[gnu::noinline]] void Interp::exec_rest(const ast::Stmt& s, Env* env, std::vector<ShapePtr>& out) {
    switch (s.kind) {
        case ast::StmtKind::Empty:
            return;
        case ast::StmtKind::Let:
        case ast::StmtKind::Var: {
            if (s.kind == ast::StmtKind::Var && !env->field_scope)
                fail(s.loc, "'var' is only allowed inside a field block; use 'let' (outside a field block a value never changes)");
            // Built-in functions keep their names; the constants (pi, tau, e, time) may be shadowed.
            if (find_builtin(s.name) && !redefinable_builtin(s.name))
                fail(s.name_loc, fmt::format("'{}' is a built-in name and cannot be redefined", s.name));
            auto it = env->vars.find(s.name);
            if (it != env->vars.end())
                fail(s.name_loc, fmt::format("'{}' is already defined in this scope ({})", s.name, where_defined(it->second.loc, s.name_loc)));
            Value v;
            bool defined = false;
            if (env == main_env && s.kind == ast::StmtKind::Let)
                for (size_t k = 0; k < opts.defines.size() && !defined; ++k)
                    if (opts.defines[k].name == s.name) v = defined_value(k, s, env), defined = true;
            if (!defined) {
                // A param(...) here is named after the let (a -D value above replaces it).
                const std::string outer = param_let;
                param_let = env == main_env && s.kind == ast::StmtKind::Let ? s.name : "";
                params_in_let = 0;
                try {
                    v = eval(*s.value, env);
                } catch (...) {
                    param_let = outer;
                    throw;
                }
                param_let = outer;
            }
            env->vars[s.name] = Binding{std::move(v), s.kind == ast::StmtKind::Var, s.name_loc};
            return;
        }
        case ast::StmtKind::Assign: {
            Binding* b = env->find(s.name);
            if (!b && failed_lets.count(s.name)) throw CompileError(std::vector<Diagnostic>{});  // its error is out already
            if (!b)
                fail(s.name_loc, fmt::format("unknown variable '{0}' (a new name is declared with `let {0} = ...;`, or `var {0} = ...;` "
                                             "inside a field to change it later)",
                                             s.name));
            if (!b->mut && env->field_scope && b->field_param)
                fail(s.name_loc, fmt::format("'{0}' is the field's point, which does not change; copy it to change it: `var q = {0};`", s.name));
            if (!b->mut && env->field_scope)
                fail(s.name_loc, fmt::format("'{}' is a constant (declared with let at line {}); declare it with var to reassign it", s.name, b->loc.line));
            if (!b->mut)  // (outside a field block nothing changes: OpenSCAD's rule too)
                fail(s.name_loc, fmt::format("'{}' is a constant (declared with let at line {}): a value outside a field block never "
                                             "changes; give the new value a new name, or compute it in one expression (a list "
                                             "comprehension, a recursive def)",
                                             s.name, b->loc.line));
            Value v = eval(*s.value, env);
            if (v.t != b->value.t || v.n != b->value.n)
                fail(s.value->loc, fmt::format("'{}' holds {}; it cannot be assigned {}", s.name, describe(b->value), describe(v)));
            b->value = std::move(v);
            return;
        }
        case ast::StmtKind::Def: {
            check_shape_before_shape(*s.value);
            if (find_builtin(s.name) && !redefinable_builtin(s.name))
                fail(s.name_loc, fmt::format("'{}' is a built-in name and cannot be redefined", s.name));
            auto it = env->vars.find(s.name);
            if (it != env->vars.end())
                fail(s.name_loc, fmt::format("'{}' is already defined in this scope ({})", s.name, where_defined(it->second.loc, s.name_loc)));
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
            std::string ext = target.extension().string();
            for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
            if (ext == ".scad") fail(s.loc, "import reads sdfc scripts, not OpenSCAD's .scad files: port it (a module or function is a def)");
            for (const char* mesh : {".stl", ".obj", ".off", ".3mf", ".ply", ".amf", ".dxf", ".svg"})
                if (ext == mesh) fail(s.loc, fmt::format("import reads sdfc scripts (their defs and lets): a {} file cannot be imported", ext.substr(1)));
            std::error_code ec;
            std::string key = fs::weakly_canonical(target, ec).string();
            if (ec) fail(s.loc, fmt::format("cannot open '{}': {}", target.string(), ec.message()));
            // (each file passes on the names of those it imports: a chain costs its depth squared)
            if (import_stack.size() >= size_t(opts.limits.max_nesting))
                fail(s.loc, fmt::format("imports nested deeper than {} files ({})", opts.limits.max_nesting,
                                        opts.limits.max_nesting >= ast::ParseOptions::kMostNesting ? "the most --max-nesting allows"
                                                                                                   : "raise it with --max-nesting"));
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
            for (const auto& [name, b] : defs->vars) {
                auto have = env->vars.find(name);
                if (have == env->vars.end()) {
                    env->vars[name] = b;
                    continue;
                }
                // A let of this file is an error, as the other order (import, then let) is.
                // A def of this file wins (defs run first, so it did in either order), and
                // so does the first of two imports.
                const Binding& h = have->second;
                const bool same = h.loc.file == b.loc.file && h.loc.line == b.loc.line && h.loc.col == b.loc.col;
                if (!same && h.loc.file == s.loc.file && h.value.t != VT::Function)
                    fail(s.loc, fmt::format("this import defines '{}' ({}:{}), which is already defined in this scope ({})", name,
                                            b.loc.file ? b.loc.file->path : std::string("?"), b.loc.line, where_defined(h.loc, s.loc)));
            }
            return;
        }
        case ast::StmtKind::Expr:
            return;  // (exec handles it)
        case ast::StmtKind::If: {
            Value c = eval(*s.value, env);
            std::optional<bool> k = const_truth(c, s.value->loc);
            if (k) {
                const ast::Stmt* branch = *k ? s.then_branch.get() : s.else_branch.get();
                const size_t before = out.size();
                if (branch) {
                    Env* inner = new_env(env);
                    exec(*branch, inner, out);
                }
                if (out.size() == before && may_add_shapes(s)) out.push_back(union_of({}, s.loc));
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
            if (iters.size() == 1) {
                out.push_back(iters[0]);
                return;
            }
            if (iters.empty() && !may_add_shapes(s)) return;
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
            const double n = r.count();
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

// ---------------------------------------------------------------- blocks

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
