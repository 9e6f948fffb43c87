// Builds the AST from the PEGTL grammar in grammar/sdf_grammar.hpp.
//
// How it works: every rule with an action reduces the items that its sub-rules pushed onto
// a value stack (State::items) into one item (an expression, a statement, an argument...).
// The control (base_control below) gives each such rule a frame, the stack size when the
// rule started, so an action knows which items are its own; postfix actions (call, index,
// swizzle, ternary tail, modifier target) also take the one item just below their frame, the
// expression they extend. The control also
//   - truncates the stack when a rule fails, so a backtracking alternative leaves nothing,
//   - forces rewinding for error-point rules so errors point where the rule started,
//   - counts nesting (rules deriving from grammar::nesting) against the depth limit,
// and raises the messages of grammar/error_messages.hpp through tao::pegtl::must_if.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string_view>

#include <fmt/format.h>

#include "grammar/error_messages.hpp"
#include "grammar/sdf_grammar.hpp"
#include "lang/ast.hpp"

namespace sdfc::ast {
namespace {

namespace pegtl = tao::pegtl;
namespace g = sdfc::grammar;

// ---------------------------------------------------------------- the value stack

enum class Tag : uint8_t { Expr, Stmt, Arg, Param, Binding, Name, Op, RangeMark, ResultMark };

// Arg, Param and Binding items keep their parts in `name` and `expr` (the value, the
// default, the iterable) until their parent node takes them.
struct Item {
    Tag tag = Tag::Expr;
    BinOp op = BinOp::Add;
    uint32_t height = 1; // height of the subtree
    Loc loc;             // first character (for an Expr: including enclosing parentheses)
    ExprPtr expr;
    StmtPtr stmt;
    std::string name;
};

struct State {
    const SourceFile* file = nullptr;
    unsigned max_depth = 256;
    unsigned max_height = 1024;
    std::vector<Item> items;
    std::vector<size_t> frames;
    std::vector<Item> taken;  // reused by take()
    unsigned depth = 0;
    const char* block_end = nullptr;  // where the last block's `}` (and the space after it) ended

    bool just_after_block(const char* current) const { return current == block_end; }

    Loc loc(const pegtl::position& p) const {
        return Loc{file, static_cast<uint32_t>(p.line), static_cast<uint32_t>(p.column)};
    }

    // The items of the current rule (pushed since it started), removed from the stack.
    // Valid until the next take(); an action takes once.
    std::vector<Item>& take() {
        size_t f = frames.back();
        taken.clear();
        taken.insert(taken.end(), std::make_move_iterator(items.begin() + static_cast<ptrdiff_t>(f)),
                     std::make_move_iterator(items.end()));
        items.resize(f);
        return taken;
    }
    // The item just below the current rule's frame (what a postfix rule extends), removed.
    Item take_below() {
        Item it = std::move(items.back());
        items.pop_back();
        return it;
    }

    void check_height(uint32_t height, Loc loc) const {
        if (height > max_height)
            throw CompileError(loc, fmt::format("expression nested deeper than {} levels (split long chains of "
                                                "operators with `let`)",
                                                max_height));
    }
    void push_expr(ExprPtr e, Loc start, uint32_t height) {
        check_height(height, start);
        Item it;
        it.tag = Tag::Expr;
        it.loc = start;
        it.height = height;
        it.expr = std::move(e);
        items.push_back(std::move(it));
    }
    void push_stmt(StmtPtr s, uint32_t height) {
        if (height > max_height)
            throw CompileError(s->loc, fmt::format("statement nested deeper than {} levels", max_height));
        Item it;
        it.tag = Tag::Stmt;
        it.loc = s->loc;
        it.height = height;
        it.stmt = std::move(s);
        items.push_back(std::move(it));
    }
    void push_mark(Tag t) {
        Item it;
        it.tag = t;
        items.push_back(std::move(it));
    }
};

ExprPtr make(ExprKind k, Loc loc) {
    auto e = std::make_unique<Expr>();
    e->kind = k;
    e->loc = loc;
    return e;
}

StmtPtr make_stmt(StmtKind k, Loc loc) {
    auto s = std::make_unique<Stmt>();
    s->kind = k;
    s->loc = loc;
    return s;
}

uint32_t max_height(const std::vector<Item>& items) {
    uint32_t h = 0;
    for (const auto& it : items) h = std::max(h, it.height);
    return h;
}

// ---------------------------------------------------------------- actions

template <typename Rule>
struct action : pegtl::nothing<Rule> {};

template <>
struct action<g::number_lit> {
    template <typename In>
    static void apply(const In& in, State& st) {
        double v = 0;
        auto [ptr, ec] = std::from_chars(in.begin(), in.end(), v);
        Loc loc = st.loc(in.position());
        if (ec == std::errc::result_out_of_range || !std::isfinite(v))
            throw CompileError(loc, fmt::format("number '{}' is out of range", in.string_view()));
        if (ec != std::errc() || ptr != in.end()) throw CompileError(loc, fmt::format("invalid number '{}'", in.string_view()));
        auto e = make(ExprKind::Number, loc);
        e->number = v;
        st.push_expr(std::move(e), loc, 1);
    }
};

template <>
struct action<g::string_text> {
    template <typename In>
    static void apply(const In& in, State& st) {
        std::string_view raw = in.string_view();
        raw = raw.substr(1, raw.size() - 2);  // the quotes
        std::string text;
        text.reserve(raw.size());
        for (size_t i = 0; i < raw.size(); ++i) {
            if (raw[i] != '\\') {
                text += raw[i];
                continue;
            }
            char c = raw[++i];  // the grammar guarantees a valid escape
            text += c == 'n' ? '\n' : c == 't' ? '\t' : c;
        }
        Loc loc = st.loc(in.position());
        auto e = make(ExprKind::String, loc);
        e->text = std::move(text);
        st.push_expr(std::move(e), loc, 1);
    }
};

template <bool Value>
struct bool_action {
    template <typename In>
    static void apply(const In& in, State& st) {
        Loc loc = st.loc(in.position());
        auto e = make(ExprKind::Bool, loc);
        e->boolean = Value;
        st.push_expr(std::move(e), loc, 1);
    }
};
template <> struct action<g::true_lit> : bool_action<true> {};
template <> struct action<g::false_lit> : bool_action<false> {};

template <>
struct action<g::ident_name> {
    template <typename In>
    static void apply(const In& in, State& st) {
        Loc loc = st.loc(in.position());
        auto e = make(ExprKind::Ident, loc);
        e->text = in.string();
        st.push_expr(std::move(e), loc, 1);
    }
};

// Names of declarations, arguments, parameters, loop variables and field parameters.
struct name_action {
    template <typename In>
    static void apply(const In& in, State& st) {
        Item it;
        it.tag = Tag::Name;
        it.loc = st.loc(in.position());
        it.name = in.string();
        st.items.push_back(std::move(it));
    }
};
template <> struct action<g::arg_name> : name_action {};
template <> struct action<g::decl_name> : name_action {};
template <> struct action<g::param_name> : name_action {};
template <> struct action<g::loop_var> : name_action {};
template <> struct action<g::field_param_name> : name_action {};

template <BinOp Op>
struct op_action {
    template <typename In>
    static void apply(const In& in, State& st) {
        Item it;
        it.tag = Tag::Op;
        it.loc = st.loc(in.position());
        it.op = Op;
        st.items.push_back(std::move(it));
    }
};
template <> struct action<g::op_or> : op_action<BinOp::Or> {};
template <> struct action<g::op_and> : op_action<BinOp::And> {};
template <> struct action<g::op_eq> : op_action<BinOp::Eq> {};
template <> struct action<g::op_ne> : op_action<BinOp::Ne> {};
template <> struct action<g::op_lt> : op_action<BinOp::Lt> {};
template <> struct action<g::op_le> : op_action<BinOp::Le> {};
template <> struct action<g::op_gt> : op_action<BinOp::Gt> {};
template <> struct action<g::op_ge> : op_action<BinOp::Ge> {};
template <> struct action<g::op_add> : op_action<BinOp::Add> {};
template <> struct action<g::op_sub> : op_action<BinOp::Sub> {};
template <> struct action<g::op_mul> : op_action<BinOp::Mul> {};
template <> struct action<g::op_div> : op_action<BinOp::Div> {};
template <> struct action<g::op_mod> : op_action<BinOp::Mod> {};

// `a op b op c` -> ((a op b) op c). A Binary node's loc is its operator (where errors such
// as "division by zero" belong); the item keeps the first character for enclosing nodes.
struct fold_action {
    template <typename In>
    static void apply(const In&, State& st) {
        if (st.items.size() - st.frames.back() == 1) return;
        auto& items = st.take();
        Item acc = std::move(items[0]);
        for (size_t i = 1; i + 1 < items.size(); i += 2) {
            Item& rhs = items[i + 1];
            auto e = make(ExprKind::Binary, items[i].loc);
            e->bin_op = items[i].op;
            e->lhs = std::move(acc.expr);
            e->rhs = std::move(rhs.expr);
            acc.height = 1 + std::max(acc.height, rhs.height);
            acc.expr = std::move(e);
            st.check_height(acc.height, acc.loc);
        }
        st.push_expr(std::move(acc.expr), acc.loc, acc.height);
    }
};
template <> struct action<g::mul_level> : fold_action {};
template <> struct action<g::add_level> : fold_action {};
template <> struct action<g::cmp_level> : fold_action {};
template <> struct action<g::and_level> : fold_action {};
template <> struct action<g::or_level> : fold_action {};

template <UnOp Op>
struct unary_action {
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        Loc loc = st.loc(in.position());
        auto e = make(ExprKind::Unary, loc);
        e->un_op = Op;
        e->lhs = std::move(items[0].expr);
        st.push_expr(std::move(e), loc, items[0].height + 1);
    }
};
template <> struct action<g::neg_expr> : unary_action<UnOp::Neg> {};
template <> struct action<g::not_expr> : unary_action<UnOp::Not> {};

template <>
struct action<g::ternary_tail> {
    template <typename In>
    static void apply(const In&, State& st) {
        auto& items = st.take();
        Item cond = st.take_below();
        auto e = make(ExprKind::Ternary, cond.loc);
        uint32_t h = 1 + std::max(cond.height, max_height(items));
        e->elems.push_back(std::move(cond.expr));
        e->elems.push_back(std::move(items[0].expr));
        e->elems.push_back(std::move(items[1].expr));
        st.push_expr(std::move(e), cond.loc, h);
    }
};

// `(expr)`: the expression itself, starting at the '('.
template <>
struct action<g::paren_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        st.items.back().loc = st.loc(in.position());
    }
};

template <>
struct action<g::arg> {
    template <typename In>
    static void apply(const In&, State& st) {
        auto& items = st.take();
        Item it;
        it.tag = Tag::Arg;
        it.loc = items[0].loc;  // the name, or the value of a positional argument
        if (items.size() == 2) it.name = std::move(items[0].name);
        it.height = items.back().height;
        it.expr = std::move(items.back().expr);
        st.items.push_back(std::move(it));
    }
};

std::vector<Arg> take_args(std::vector<Item>& items, size_t begin, size_t end) {
    std::vector<Arg> args;
    for (size_t i = begin; i < end; ++i) args.push_back(Arg{items[i].loc, std::move(items[i].name), std::move(items[i].expr)});
    return args;
}

template <>
struct action<g::call_suffix> {
    template <typename In>
    static void apply(const In&, State& st) {
        auto& items = st.take();
        Item callee = st.take_below();
        auto e = make(ExprKind::Call, callee.loc);
        uint32_t h = 1 + std::max(callee.height, max_height(items));
        e->callee = std::move(callee.expr);
        e->args = take_args(items, 0, items.size());
        st.push_expr(std::move(e), callee.loc, h);
    }
};

template <>
struct action<g::index_suffix> {
    template <typename In>
    static void apply(const In&, State& st) {
        auto& items = st.take();
        Item lhs = st.take_below();
        auto e = make(ExprKind::Index, lhs.loc);
        uint32_t h = 1 + std::max(lhs.height, items[0].height);
        e->lhs = std::move(lhs.expr);
        e->rhs = std::move(items[0].expr);
        st.push_expr(std::move(e), lhs.loc, h);
    }
};

template <>
struct action<g::swizzle_suffix> {
    template <typename In>
    static void apply(const In& in, State& st) {
        std::string_view s = in.string_view().substr(1);  // after the '.'
        size_t n = 0;
        while (n < s.size() && (std::isalnum(static_cast<unsigned char>(s[n])) || s[n] == '_')) ++n;
        Item lhs = st.take_below();
        auto e = make(ExprKind::Swizzle, lhs.loc);
        e->text = std::string(s.substr(0, n));
        e->lhs = std::move(lhs.expr);
        st.push_expr(std::move(e), lhs.loc, lhs.height + 1);
    }
};

template <>
struct action<g::range_tail> {
    template <typename In>
    static void apply(const In&, State& st) {
        st.push_mark(Tag::RangeMark);
    }
};

template <>
struct action<g::bracket_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        Loc loc = st.loc(in.position());
        bool range = !items.empty() && items.back().tag == Tag::RangeMark;
        if (range) items.pop_back();
        auto e = make(range ? ExprKind::Range : ExprKind::Vector, loc);
        uint32_t h = 1 + max_height(items);
        if (range) {
            e->elems.push_back(std::move(items.front().expr));
            e->elems.push_back(items.size() == 3 ? std::move(items[1].expr) : nullptr);
            e->elems.push_back(std::move(items.back().expr));
        } else {
            for (auto& it : items) e->elems.push_back(std::move(it.expr));
        }
        st.push_expr(std::move(e), loc, h);
    }
};

template <>
struct action<g::binding> {
    template <typename In>
    static void apply(const In&, State& st) {
        auto& items = st.take();
        Item it;
        it.tag = Tag::Binding;
        it.loc = items[0].loc;
        it.height = items[1].height;
        it.name = std::move(items[0].name);
        it.expr = std::move(items[1].expr);
        st.items.push_back(std::move(it));
    }
};

std::vector<ForBinding> take_bindings(std::vector<Item>& items) {
    std::vector<ForBinding> out;
    for (auto& it : items)
        if (it.tag == Tag::Binding) out.push_back(ForBinding{it.loc, std::move(it.name), std::move(it.expr)});
    return out;
}

template <>
struct action<g::for_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        Loc loc = st.loc(in.position());
        auto e = make(ExprKind::For, loc);
        uint32_t h = 1 + max_height(items);
        e->body = std::move(items.back().expr);
        items.pop_back();
        e->bindings = take_bindings(items);
        st.push_expr(std::move(e), loc, h);
    }
};

// elems = {cond, then, else}; else is null when absent.
template <>
struct action<g::if_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        Loc loc = st.loc(in.position());
        auto e = make(ExprKind::If, loc);
        uint32_t h = 1 + max_height(items);
        for (auto& it : items) e->elems.push_back(std::move(it.expr));
        if (e->elems.size() == 2) e->elems.push_back(nullptr);
        st.push_expr(std::move(e), loc, h);
    }
};

template <>
struct action<g::field_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        Loc loc = st.loc(in.position());
        auto e = make(ExprKind::Field, loc);
        uint32_t h = 1 + max_height(items);
        size_t n = items.size();
        e->body = std::move(items[n - 1].expr);
        e->text = std::move(items[n - 2].name);
        e->args = take_args(items, 0, n - 2);
        st.push_expr(std::move(e), loc, h);
    }
};

template <>
struct action<g::rbrace> {
    template <typename In>
    static void apply(const In& in, State& st) {
        st.block_end = in.end();
    }
};

template <>
struct action<g::block> {
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        Loc loc = st.loc(in.position());
        auto e = make(ExprKind::BlockExpr, loc);
        e->block = std::make_unique<Block>();
        e->block->loc = loc;
        uint32_t h = 2 + max_height(items);
        for (auto& it : items) {
            if (it.tag == Tag::Stmt)
                e->block->stmts.push_back(std::move(it.stmt));
            else
                e->block->result = std::move(it.expr);  // only ever the last item
        }
        st.push_expr(std::move(e), loc, h);
    }
};

// A modifier followed by its target.
template <>
struct action<g::apply_target> {
    template <typename In>
    static void apply(const In&, State& st) {
        auto& items = st.take();
        Item mod = st.take_below();
        Item& target = items[0];
        if (mod.expr->kind != ExprKind::Call && mod.expr->kind != ExprKind::Ident)
            throw CompileError(target.loc, "only a call or a name can be applied to a shape (is a ';' missing?)");
        auto e = make(ExprKind::Apply, mod.loc);
        uint32_t h = 1 + std::max(mod.height, target.height);
        e->lhs = std::move(mod.expr);
        e->rhs = std::move(target.expr);
        st.push_expr(std::move(e), mod.loc, h);
    }
};

// ---------------------------------------------------------------- statement actions

template <StmtKind Kind>
struct binding_stmt_action {  // let / var / assign: [name, value]
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        auto s = make_stmt(Kind, st.loc(in.position()));
        s->name = std::move(items[0].name);
        s->name_loc = items[0].loc;
        s->value = std::move(items[1].expr);
        st.push_stmt(std::move(s), items[1].height + 1);
    }
};
template <> struct action<g::let_stmt> : binding_stmt_action<StmtKind::Let> {};
template <> struct action<g::var_stmt> : binding_stmt_action<StmtKind::Var> {};
template <> struct action<g::assign_stmt> : binding_stmt_action<StmtKind::Assign> {};

struct param_action {  // [name, default?]
    template <typename In>
    static void apply(const In&, State& st) {
        auto& items = st.take();
        Item it;
        it.tag = Tag::Param;
        it.loc = items[0].loc;
        it.height = items.back().height;
        it.name = std::move(items[0].name);
        if (items.size() == 2) it.expr = std::move(items[1].expr);
        st.items.push_back(std::move(it));
    }
};
template <> struct action<g::expect_param> : param_action {};

template <>
struct action<g::def_stmt> {  // [name, params..., value]
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        auto s = make_stmt(StmtKind::Def, st.loc(in.position()));
        s->name = std::move(items.front().name);
        s->name_loc = items.front().loc;
        for (size_t i = 1; i + 1 < items.size(); ++i)
            s->params.push_back(Param{items[i].loc, std::move(items[i].name), std::move(items[i].expr)});
        s->value = std::move(items.back().expr);
        st.push_stmt(std::move(s), 1 + max_height(items));
    }
};

template <>
struct action<g::import_stmt> {
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        auto s = make_stmt(StmtKind::Import, st.loc(in.position()));
        s->name = std::move(items[0].expr->text);
        s->name_loc = items[0].loc;
        st.push_stmt(std::move(s), 1);
    }
};

template <>
struct action<g::if_stmt> {  // [cond, then, else?]
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        auto s = make_stmt(StmtKind::If, st.loc(in.position()));
        s->value = std::move(items[0].expr);
        s->then_branch = std::move(items[1].stmt);
        if (items.size() > 2) s->else_branch = std::move(items[2].stmt);
        st.push_stmt(std::move(s), 1 + max_height(items));
    }
};

template <>
struct action<g::for_stmt> {  // [bindings..., body]
    template <typename In>
    static void apply(const In& in, State& st) {
        auto& items = st.take();
        auto s = make_stmt(StmtKind::For, st.loc(in.position()));
        uint32_t h = 1 + max_height(items);
        s->body = std::move(items.back().stmt);
        items.pop_back();
        s->bindings = take_bindings(items);
        st.push_stmt(std::move(s), h);
    }
};

template <>
struct action<g::empty_stmt> {
    template <typename In>
    static void apply(const In& in, State& st) {
        st.push_stmt(make_stmt(StmtKind::Empty, st.loc(in.position())), 1);
    }
};

template <>
struct action<g::expr_stmt> {
    template <typename In>
    static void apply(const In&, State& st) {
        auto& items = st.take();
        auto s = make_stmt(StmtKind::Expr, items[0].loc);
        s->value = std::move(items[0].expr);
        st.push_stmt(std::move(s), items[0].height + 1);
    }
};

template <>
struct action<g::block_result> {
    template <typename In>
    static void apply(const In&, State& st) {
        st.push_mark(Tag::ResultMark);
    }
};

// Inside a block: a statement, or (followed directly by '}') the block's result.
template <>
struct action<g::block_expr_item> {
    template <typename In>
    static void apply(const In& in, State& st) {
        if (st.items.back().tag == Tag::ResultMark) {
            st.items.pop_back();  // leave the expression for the block
            return;
        }
        action<g::expr_stmt>::apply(in, st);
    }
};

// ---------------------------------------------------------------- control

template <typename Rule>
struct base_control : pegtl::normal<Rule> {
    template <pegtl::apply_mode A, pegtl::rewind_mode M, template <typename...> class Action,
              template <typename...> class Control, typename ParseInput>
    static bool match(ParseInput& in, State& st) {
        // Error points rewind on failure so that the error is reported where they started.
        constexpr bool error_point = g::error_message<Rule> != nullptr;
        constexpr pegtl::rewind_mode mode = error_point ? pegtl::rewind_mode::required : M;
        constexpr bool nests = std::is_base_of_v<g::nesting, Rule>;
        constexpr bool framed = !std::is_base_of_v<pegtl::nothing<Rule>, Action<Rule>>;
        // PEGTL rewinds a rule with an action only after its failure hook ran, so the error
        // would point where the rule stopped, not where it started (see sdf_grammar.hpp).
        static_assert(!(error_point && framed), "an error point must not have an action");

        struct DepthGuard {
            unsigned* depth;
            ~DepthGuard() {
                if (depth) --*depth;
            }
        } guard{nullptr};
        if constexpr (nests) {
            if (st.depth >= st.max_depth)
                throw CompileError(st.loc(in.position()), fmt::format("nesting deeper than {} levels", st.max_depth));
            ++st.depth;
            guard.depth = &st.depth;
        }
        const size_t mark = st.items.size();
        if constexpr (framed) st.frames.push_back(mark);
        const bool ok = pegtl::normal<Rule>::template match<A, mode, Action, Control>(in, st);
        if constexpr (framed) st.frames.pop_back();
        if (!ok && st.items.size() > mark) st.items.resize(mark);
        return ok;
    }
};

template <typename Rule>
struct control : pegtl::must_if<g::errors, base_control>::control<Rule> {};

// ---------------------------------------------------------------- error positions

Loc loc_at(const SourceFile& f, size_t off) {
    auto it = std::upper_bound(f.line_starts.begin(), f.line_starts.end(), off);
    uint32_t line = static_cast<uint32_t>(it - f.line_starts.begin());
    return Loc{&f, line, static_cast<uint32_t>(off - f.line_starts[line - 1] + 1)};
}

// The end of the last token before `off` (which follows that token's whitespace and
// comments): where a missing ';' belongs.
size_t previous_token_end(std::string_view t, size_t off) {
    size_t i = 0, last = 0;
    while (i < off && i < t.size()) {
        char c = t[i];
        if (c == '/' && i + 1 < t.size() && t[i + 1] == '/') {
            while (i < t.size() && t[i] != '\n') ++i;
        } else if (c == '/' && i + 1 < t.size() && t[i + 1] == '*') {
            size_t e = t.find("*/", i + 2);
            i = e == std::string_view::npos ? t.size() : e + 2;
        } else if (c == '"') {
            ++i;
            while (i < t.size() && t[i] != '"' && t[i] != '\n') i += t[i] == '\\' ? 2 : 1;
            if (i < t.size() && t[i] == '"') ++i;
            last = i;
        } else if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f') {
            ++i;
        } else {
            last = ++i;
        }
    }
    return std::min(last, off);
}

bool token_start(unsigned char c) {
    return std::isalnum(c) || c == '_' || (c != 0 && std::strchr(".\"()[]{},;:?=!<>+-*/%&|", c) != nullptr);
}

const char* const lexical_messages[] = {
    g::error_message<g::block_comment_body>,
    g::error_message<g::string_body>,
    g::error_message<g::escape_seq>,
    g::error_message<g::exponent_digits>,
};

bool is_keyword(std::string_view w) {
    static const char* const kws[] = {"let", "def", "field", "var", "for", "if", "else", "import", "true", "false"};
    return std::find(std::begin(kws), std::end(kws), w) != std::end(kws);
}

// Turns PEGTL's error into the diagnostic a user should read.
CompileError syntax_error(const SourceFile& f, size_t off, std::string msg) {
    const std::string_view t = f.text;
    bool lexical = std::find(std::begin(lexical_messages), std::end(lexical_messages), msg) != std::end(lexical_messages);
    if (!lexical && off < t.size()) {
        unsigned char c = static_cast<unsigned char>(t[off]);
        bool lone_amp = (c == '&' || c == '|') && (off + 1 >= t.size() || t[off + 1] != static_cast<char>(c));
        if (!token_start(c) || lone_amp) {
            std::string what;
            if (c >= 0x80) {
                size_t n = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC0 ? 2 : 1;
                what = fmt::format("'{}'", t.substr(off, std::min(n, t.size() - off)));
            } else if (c < 0x20 || c == 0x7F) {
                what = fmt::format("U+{:04X}", c);
            } else if (c == '\'') {
                what = "\"'\"";
            } else {
                what = fmt::format("'{}'", static_cast<char>(c));
            }
            std::string hint = lone_amp ? fmt::format(" (did you mean '{0}{0}'?)", static_cast<char>(c))
                               : c == '\'' ? " (strings are written in double quotes)"
                                           : "";
            return CompileError(loc_at(f, off), fmt::format("unexpected character {}{}", what, hint));
        }
    }
    if (msg == g::error_message<g::expect_semi>) return CompileError(loc_at(f, previous_token_end(t, off)), msg);
    if (msg.rfind("expected a ", 0) == 0 && msg.find("name") != std::string::npos && off < t.size()) {
        size_t e = off;
        while (e < t.size() && (std::isalnum(static_cast<unsigned char>(t[e])) || t[e] == '_')) ++e;
        std::string_view word = t.substr(off, e - off);
        if (is_keyword(word)) msg += fmt::format(" ('{}' is a keyword)", word);
    }
    return CompileError(loc_at(f, off), std::move(msg));
}

}  // namespace

std::unique_ptr<Module> parse(const SourceFile& file, const ParseOptions& opts) {
    State st;
    st.file = &file;
    st.max_depth = static_cast<unsigned>(std::max(opts.max_nesting, 1));
    // Operator chains make trees taller than their nesting; later stages recurse over the
    // tree, so its height is bounded too.
    st.max_height = std::max(4 * st.max_depth, 64u);
    pegtl::memory_input<pegtl::tracking_mode::eager, pegtl::eol::lf_crlf> in(file.text.data(), file.text.size(),
                                                                            file.path);
    try {
        pegtl::parse<g::grammar, action, control>(in, st);
    } catch (const pegtl::parse_error& e) {
        const auto& p = e.positions().front();
        throw syntax_error(file, p.byte, std::string(e.message()));
    }
    auto m = std::make_unique<Module>();
    m->file = &file;
    for (auto& it : st.items) m->stmts.push_back(std::move(it.stmt));
    return m;
}

}  // namespace sdfc::ast
