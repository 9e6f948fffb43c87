// Internal to lang/: the interpreter's state, shared by interpreter.cpp (statements and
// blocks), expressions.cpp (expressions, calls, operators) and builtins.cpp (the built-in
// shapes, operations, settings and math).
#pragma once
#include <deque>
#include <functional>
#include <optional>
#include <set>
#include <tuple>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

#include "lang/interpreter.hpp"
#include "lang/value.hpp"

namespace sdfc {

struct Binding {
    Value value;
    bool mut = false;
    Loc loc;
    bool field_param = false;  // a field's point (p in `field (p) -> ...`)
};

struct Env {
    Env* parent = nullptr;
    std::unordered_map<std::string, Binding> vars;
    bool field_scope = false;  // inside a field body: `var` and assignment allowed
    Binding* find(const std::string& name) {
        for (Env* e = this; e; e = e->parent) {
            auto it = e->vars.find(name);
            if (it != e->vars.end()) return &it->second;
        }
        return nullptr;
    }
};

// The shapes of compiler/scene/shapes.def that the script names, then lang/builtins.def.
enum class Builtin : uint16_t {
#define SDFC_SHAPE(kind, ...) kind,
#define SDFC_INNER_SHAPE(...)
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
#define SDFC_BUILTIN(id, name, kind) id,
#include "lang/builtins.def"
#undef SDFC_BUILTIN
};

enum class BuiltinKind { Math, Shape, Modifier, Setting, MaterialCtor };

// Parameter types of builtins.
enum class PT { Num, Vec3, NumOrVec3, NumOrVec2, Vec, Bool, String, Material, Any };

// The checks of a shape's constant arguments (the Checks column of shapes.def).
namespace param_check {
enum : uint8_t { None = 0, Finite = 1, NonNeg = 2, Positive = 4, Angle = 8, Nonzero = 32 };
}

struct ParamSpec {
    const char* name;
    PT type;
    bool has_default = false;
    std::array<float, 3> def{};
    uint8_t checks = param_check::None;
    bool stored = true;  // a shape's: in Shape::params as given (shapes.def's SDFC_P)
};

enum class ShapeBuild { Table, Custom };

struct BuiltinInfo {
    Builtin id;
    const char* name;
    BuiltinKind kind;
    std::vector<ParamSpec> params;
    ShapeKind shape = ShapeKind::Empty;  // Shape and Modifier: the kind it makes
    ShapeBuild build = ShapeBuild::Table;
};

const BuiltinInfo* find_builtin(std::string_view name);
// Whether a script may define the name itself: the built-ins LANGUAGE.md does not name
// (sdfc's later additions: len, concat, ...), so that a script written against the contract
// with its own `def norm(v) = ...` keeps working; its definition wins where it is seen.
inline bool redefinable_builtin(std::string_view name) {
    for (std::string_view n : {"param", "len", "concat", "lookup", "norm"})
        if (n == name) return true;
    return false;
}
// The function value of a builtin (one, shared: Callable is immutable).
const std::shared_ptr<const Callable>& builtin_callable(Builtin id);
const BuiltinInfo& builtin_info(Builtin id);
const std::vector<std::string>& builtin_names();

// The built-in constants (a let may shadow them).
inline constexpr std::string_view kConstantNames[] = {"time", "pi", "tau", "e"};
// "unknown name 'NAME'" and its hint, for the error and for the warning of code that has not
// run: an OpenSCAD habit's, else the nearest of the built-ins, the constants and `names`.
std::string unknown_name_message(const std::string& name, const std::vector<std::string>& names);

// After a run without errors: a warning for each name used but bound nowhere in `modules`
// (code that has not run; lang/unknown_names.cpp).
void warn_unknown_names(const std::deque<std::unique_ptr<ast::Module>>& modules, std::vector<Diagnostic>& warnings);

class Interp {
public:
    Interp(SourceManager& sm, const InterpretOptions& opts);

    Scene run(const SourceFile& file);

    // --- evaluation (statements and blocks: interpreter.cpp; the rest: expressions.cpp)
    // eval and exec are what nesting recurses through (blocks, modifiers, statements): they
    // stay small frames and hand every other kind to eval_rest / exec_rest, whose frames
    // (large under AddressSanitizer) are then not paid once per nesting level.
    Value eval(const ast::Expr& e, Env* env);
    Value eval_rest(const ast::Expr& e, Env* env);
    Value eval_block(const ast::Block& b, Env* env, bool field_scope);
    void exec(const ast::Stmt& s, Env* env, std::vector<ShapePtr>& out);
    void exec_rest(const ast::Stmt& s, Env* env, std::vector<ShapePtr>& out);
    [[noreturn]] void bad_statement(const ast::Stmt& s, const Value& v);  // neither a shape nor a setting
    void check_shape_before_shape(const ast::Expr& e);  // a def's `torus(1, 0.1) sphere(1)`: a ';' missing
    void exec_stmts(const std::vector<ast::StmtPtr>& stmts, Env* env, std::vector<ShapePtr>& out);
    Value call_value(const Value& callee, const std::vector<ast::Arg>& args, Env* env, Loc loc);
    // `last`: the value of the last parameter when no argument gives it (a user modifier's target).
    Value call_user(const Callable& fn, const std::vector<ast::Arg>& args, Env* env, Loc loc, const Value* last = nullptr);
    CompileError called_from(const CompileError& e, const Callable& fn, Loc call);
    Value apply(const ast::Expr& e, Env* env);
    // Runs body once per combination of the bindings (the first varies slowest), each in a
    // fresh scope; enforces the loop limits.
    void run_for(const std::vector<ast::ForBinding>& bindings, Env* env, Loc loc, const std::function<void(Env*)>& body);
    ShapePtr to_shape(const Value& v, Loc loc, const char* what);
    // The target of an operation (`translate(v) ...`), evaluated with the operation's name
    // on `targets` (a setting there warns: no operation moves a light or the camera).
    Value eval_target(const ast::Expr& target, Env* env, const std::string& op);
    std::vector<std::string> targets;
    void note_setting_in_target(const BuiltinInfo& info, Loc loc);
    ShapePtr union_of(std::vector<ShapePtr> shapes, Loc loc);
    ShapePtr choose(NodeId cond, ShapePtr a, ShapePtr b, Loc loc);  // a Choose shape (cond on time alone)

    // --- builtins (builtins.cpp)
    Value call_builtin(const BuiltinInfo& info, const std::vector<ast::Arg>& args, Env* env, Loc loc);
    ShapePtr apply_modifier(const ModifierVal& m, ShapePtr target, Loc loc);
    Value call_math(const BuiltinInfo& info, std::vector<Value>& args, const std::vector<Loc>& locs, Loc loc);
    // A colour name (CSS, or #rrggbb) as linear RGB (lang/colours.cpp); an error at loc if unknown.
    Value colour_name(const std::string& name, Loc loc);
    // A warning, kept once per place and text (code in a loop or a def called many times
    // would otherwise keep one per run of it).
    void warn(Loc loc, std::string message);
    std::set<std::tuple<const SourceFile*, uint32_t, uint32_t, std::string>> warned;

    // --- helpers
    [[noreturn]] void fail(Loc loc, std::string msg);
    NodeId num(const Value& v, Loc loc, const char* what);          // a Number (or Bool)
    float const_num(const Value& v, Loc loc, const char* what);     // a constant Number
    Vec3N vec3(const Value& v, Loc loc, const char* what, bool broadcast);
    NodeId truth(const Value& v, Loc loc);                          // condition as 0/1 node
    std::optional<bool> const_truth(const Value& v, Loc loc);
    Value binary(ast::BinOp op, const Value& a, const Value& b, Loc loc);
    Value unary(ast::UnOp op, const Value& a, Loc loc);
    Value list_value(std::vector<Value> items, Loc loc);
    Value lookup(std::vector<Value>& args, const std::vector<Loc>& locs, Loc loc);
    Value componentwise(const Value& a, Loc loc, const std::function<NodeId(NodeId)>& f);
    Value componentwise2(const Value& a, const Value& b, Loc loc, const std::function<NodeId(NodeId, NodeId)>& f);
    NodeId checked(NodeId n, Loc loc);  // a constant must be finite
    ShapePtr make_shape(Shape s);
    std::string describe(const Value& v);
    void check_limit_iterations(long n, Loc loc);
    void check_list_size(size_t n, Loc loc);
    void count_calls(size_t n, Loc loc);  // function calls, field bodies, shapes applied to points

    // -D: the main script's top-level env, which defines were used, and the override.
    Env* main_env = nullptr;
    // Names whose top-level let, var, assignment or def failed (reported once), and whether an
    // import did: a use of such a name (after a failed import, of any unknown name) is skipped
    // quietly, not reported again as an unknown name.
    std::set<std::string> failed_lets;
    bool failed_import = false;
    std::vector<bool> define_used;
    Value defined_value(size_t k, const ast::Stmt& let, Env* env);
    void check_defines_used(Env* top);
    // param(...): the top-level let whose value is being computed ("" elsewhere).
    std::string param_let;
    int params_in_let = 0;     // param(...) calls in param_let's value: one names its slider
    bool param_fixed = false;  // -D gave the let its value: param(...) is a number
    // glsl's -D on `let n = param(...)`: the slider stays and starts at -D's value.
    std::optional<float> param_start;
    Value make_param(std::vector<Value>& args, const std::vector<Loc>& locs, Loc loc);

    SourceManager& sm;
    InterpretOptions opts;
    std::shared_ptr<Graph> g;
    Scene scene;
    Loc camera_at, render_at, ambient_at, background_at;

    std::deque<std::unique_ptr<Env>> envs;
    std::deque<std::unique_ptr<ast::Module>> modules;
    Env* new_env(Env* parent, bool field_scope = false);
    // Scopes are freed when a loop iteration or a call ends (release_envs(size before it)),
    // unless a closure (a def, a field, an import) may still reach them: pin_envs() keeps
    // every scope that exists at that point.
    size_t pinned_envs = 0;
    void pin_envs() { pinned_envs = envs.size(); }
    void release_envs(size_t mark) {
        if (pinned_envs <= mark && envs.size() > mark) envs.resize(mark);
    }

    int call_depth = 0;
    long total_iterations = 0;
    size_t total_calls = 0;
    size_t shape_count = 0;
    std::vector<std::string> import_stack;          // canonical paths being imported
    std::unordered_map<std::string, Env*> imported; // canonical path -> its definitions
};

}  // namespace sdfc
