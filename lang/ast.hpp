// The abstract syntax tree of a .sdf script. Built by lang/parser.cpp from the rules in
// grammar/; every node carries the Loc of its first character so diagnostics from any
// later stage point at the script. Nodes are owned by their Module and never mutated
// after parsing, so closures may keep raw pointers into the tree.
//
// Expr and Stmt nodes are allocated from a per-thread pool of same-size slots (a script is
// mostly small nodes; see NodePool in lang/node_pool.cpp): new, delete and make_unique work as
// usual, and a node may be deleted by any thread.
#pragma once
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "compiler/base/source.hpp"

namespace sdfc::ast {

struct Expr;
struct Stmt;
using ExprPtr = std::unique_ptr<Expr>;
using StmtPtr = std::unique_ptr<Stmt>;

enum class UnOp { Neg, Not };
enum class BinOp { Or, And, Eq, Ne, Lt, Le, Gt, Ge, Add, Sub, Mul, Div, Mod };

struct Arg {
    Loc loc;
    std::string name;  // empty for positional
    ExprPtr value;
};

struct Param {
    Loc loc;
    std::string name;
    ExprPtr default_value;  // may be null
};

// A `{ ... }` block: statements, and optionally a final expression without ';' whose value
// is the block's value (used by field bodies). Without it, the block's value is the union
// of the shapes its statements add.
struct Block {
    Loc loc;
    std::vector<StmtPtr> stmts;
    ExprPtr result;  // may be null
};

enum class ExprKind {
    Number,    // number
    Bool,      // boolean
    String,    // text
    Ident,     // name
    Vector,    // elems: [a, b, c]
    Range,     // lhs : [step] : rhs  ->  elems = {start, step?, end}; step null when absent
    Unary,     // un_op, lhs
    Binary,    // bin_op, lhs, rhs; loc is the operator's (errors about the operation point there)
    Ternary,   // cond ? lhs : rhs  -> elems = {cond, then, else}
    Call,      // callee(args)
    Index,     // lhs[rhs]
    Swizzle,   // lhs.name
    Apply,     // modifier target: lhs is the modifier (a Call or Ident), rhs is the target
    BlockExpr, // { stmts; result }
    Field,     // field(args) (param) -> body
    If,        // if (cond) then-expr else else-expr, in expression position: elems = {cond, then, else?}
    For,       // for (bindings) body, in modifier-target position
};

struct ForBinding {
    Loc loc;
    std::string name;
    ExprPtr iterable;  // a range or a vector
};

struct Expr {
    ExprKind kind;
    Loc loc;
    double number = 0;
    bool boolean = false;
    std::string text;   // String contents (unescaped), Ident name, Swizzle letters, Field param name
    UnOp un_op = UnOp::Neg;
    BinOp bin_op = BinOp::Add;
    ExprPtr lhs, rhs;
    std::vector<ExprPtr> elems;
    ExprPtr callee;
    std::vector<Arg> args;          // Call args, Field args (bound = ...)
    std::unique_ptr<Block> block;   // BlockExpr, For body (as block)
    std::vector<ForBinding> bindings;  // For
    ExprPtr body;                   // Field body, For body

    static void* operator new(std::size_t size);
    static void operator delete(void* p, std::size_t size) noexcept;
};

enum class StmtKind {
    Let,     // let name = value;
    Var,     // var name = value;   (inside field blocks)
    Assign,  // name = value;
    Def,     // def name(params) = value;
    Import,  // import "path";
    Expr,    // expression statement (shapes, settings calls)
    If,      // if (cond) then_branch [else else_branch]
    For,     // for (bindings) body
    Empty,   // ;
};

struct Stmt {
    StmtKind kind;
    Loc loc;
    std::string name;          // Let/Var/Assign/Def name; Import path
    Loc name_loc;
    std::vector<Param> params; // Def
    ExprPtr value;             // Let/Var/Assign/Def value; Expr expression; If condition
    StmtPtr then_branch, else_branch;  // If
    std::vector<ForBinding> bindings;  // For
    StmtPtr body;              // For

    static void* operator new(std::size_t size);
    static void operator delete(void* p, std::size_t size) noexcept;
};

struct Module {
    const SourceFile* file = nullptr;
    std::vector<StmtPtr> stmts;
};

// Parses a whole file. Throws CompileError (the first syntax error; message keyed by the
// grammar rule that failed, e.g. "expected ')'").
struct ParseOptions {
    int max_nesting = 256;  // parentheses, brackets, blocks and modifier chains together
    static constexpr int kMostNesting = 10000;  // the most --max-nesting takes
};
std::unique_ptr<Module> parse(const SourceFile& file, const ParseOptions& opts = {});

// A readable, stable listing of the tree (`sdfc compile --emit ast`).
std::string dump(const Module& m);

}  // namespace sdfc::ast
