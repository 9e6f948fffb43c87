// The parser's actions: each reduces the items its rule's sub-rules pushed onto the value
// stack (parse_stack.hpp) into one expression, statement, argument... Private to
// lang/parser.cpp, the one translation unit that instantiates the grammar (hence the
// unnamed namespace); see the top of parser.cpp.
#pragma once
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "grammar/sdf_grammar.hpp"
#include "lang/ast.hpp"
#include "lang/parse_stack.hpp"

namespace sdfc::ast {
namespace {

namespace pegtl = tao::pegtl;
namespace g = sdfc::grammar;

template <typename Rule>
struct action : pegtl::nothing<Rule> {};

// Digits with an optional '.' and fraction, at most 15 digits in all: the value is exact
// as an integer and a power of ten, so one division rounds it exactly as from_chars would.
bool simple_number(std::string_view s, double& v) {
    if (s.size() > 16) return false;
    uint64_t m = 0;
    int digits = 0, frac = -1;
    for (char c : s) {
        if (c >= '0' && c <= '9') {
            m = m * 10 + static_cast<uint64_t>(c - '0');
            ++digits;
            if (frac >= 0) ++frac;
        } else if (c == '.' && frac < 0) {
            frac = 0;
        } else {
            return false;  // an exponent
        }
    }
    if (digits == 0 || digits > 15) return false;
    static constexpr double pow10[] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
    v = static_cast<double>(m);
    if (frac > 0) v /= pow10[frac];
    return true;
}

template <>
struct action<g::number_lit> {
    template <typename In>
    static void apply(const In& in, State& st) {
        double v = 0;
        Loc loc = st.loc_at(in.begin());
        if (!simple_number(in.string_view(), v)) {
            auto [ptr, ec] = std::from_chars(in.begin(), in.end(), v);
            if (ec == std::errc::result_out_of_range || !std::isfinite(v))
                throw CompileError(loc, fmt::format("number '{}' is out of range", in.string_view()));
            if (ec != std::errc() || ptr != in.end())
                throw CompileError(loc, fmt::format("invalid number '{}'", in.string_view()));
        }
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
        Loc loc = st.loc_at(in.begin());
        auto e = make(ExprKind::String, loc);
        e->text = std::move(text);
        st.push_expr(std::move(e), loc, 1);
    }
};

template <bool Value>
struct bool_action {
    template <typename In>
    static void apply(const In& in, State& st) {
        Loc loc = st.loc_at(in.begin());
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
        Loc loc = st.loc_at(in.begin());
        auto e = make(ExprKind::Ident, loc);
        e->text = in.string_view();
        st.push_expr(std::move(e), loc, 1);
    }
};

// Names of declarations, arguments, parameters, loop variables and field parameters.
struct name_action {
    template <typename In>
    static void apply(const In& in, State& st) {
        Item& it = st.items.emplace_back();
        it.tag = Tag::Name;
        it.loc = st.loc_at(in.begin());
        it.name = in.string_view();
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
        Item& it = st.items.emplace_back();
        it.tag = Tag::Op;
        it.loc = st.loc_at(in.begin());
        it.op = Op;
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

// `a op b op c` -> ((a op b) op c): a chain [op, b, op, c...] folded onto its left operand,
// once the whole chain has been read. A Binary node's loc is its operator (where errors such
// as "division by zero" belong); the item keeps the first character for enclosing nodes.
struct fold_action {
    template <typename In>
    static void apply(const In&, State& st) {
        Item acc;
        ExprPtr lhs = st.take_below(acc);
        Frame items = st.take();
        for (size_t i = 0; i + 1 < items.size; i += 2) {
            Item& rhs = items[i + 1];
            auto e = make(ExprKind::Binary, items[i].loc);
            e->bin_op = items[i].op;
            e->lhs = std::move(lhs);
            e->rhs = own(rhs);
            acc.height = 1 + std::max(acc.height, rhs.height);
            lhs = std::move(e);
            st.check_height(acc.height, acc.loc);
        }
        st.items.resize_down(st.frame - 1);  // the chain and the left operand below it, all taken
        st.push_expr(std::move(lhs), acc.loc, acc.height);
    }
};
template <> struct action<g::mul_chain> : fold_action {};
template <> struct action<g::add_chain> : fold_action {};
template <> struct action<g::cmp_chain> : fold_action {};
template <> struct action<g::and_chain> : fold_action {};
template <> struct action<g::or_chain> : fold_action {};

template <UnOp Op>
struct unary_action {
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        Loc loc = st.loc_at(in.begin());
        auto e = make(ExprKind::Unary, loc);
        e->un_op = Op;
        e->lhs = own(items[0]);
        uint32_t h = items[0].height + 1;
        st.pop_frame();
        st.push_expr(std::move(e), loc, h);
    }
};
template <> struct action<g::neg_expr> : unary_action<UnOp::Neg> {};
template <> struct action<g::not_expr> : unary_action<UnOp::Not> {};

template <>
struct action<g::ternary_tail> {
    template <typename In>
    static void apply(const In&, State& st) {
        Item cond;
        ExprPtr c = st.take_below(cond);
        Frame items = st.take();
        auto e = make(ExprKind::Ternary, cond.loc);
        uint32_t h = 1 + std::max(cond.height, max_height(items));
        e->elems.reserve(3);
        e->elems.push_back(std::move(c));
        e->elems.push_back(own(items[0]));
        e->elems.push_back(own(items[1]));
        st.pop_frame();
        st.items.pop_back();  // cond
        st.push_expr(std::move(e), cond.loc, h);
    }
};

// `(expr)`: the expression itself, starting at the '('.
template <>
struct action<g::paren_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        st.items.back().loc = st.loc_at(in.begin());
    }
};

template <>
struct action<g::arg> {
    template <typename In>
    static void apply(const In&, State& st) {
        Frame items = st.take();
        Item it;
        it.tag = Tag::Arg;
        it.loc = items[0].loc;  // the name, or the value of a positional argument
        if (items.size == 2) it.name = items[0].name;
        it.height = items.back().height;
        it.expr = std::exchange(items.back().expr, nullptr);
        st.pop_frame();
        st.items.push_back(it);
    }
};

std::vector<Arg> take_args(const Frame& items, size_t begin, size_t end) {
    std::vector<Arg> args;
    args.reserve(end - begin);
    for (size_t i = begin; i < end; ++i) args.push_back(Arg{items[i].loc, std::string(items[i].name), own(items[i])});
    return args;
}

template <>
struct action<g::call_suffix> {
    template <typename In>
    static void apply(const In&, State& st) {
        Item callee;
        ExprPtr c = st.take_below(callee);
        Frame items = st.take();
        auto e = make(ExprKind::Call, callee.loc);
        uint32_t h = 1 + std::max(callee.height, max_height(items));
        e->callee = std::move(c);
        e->args = take_args(items, 0, items.size);
        st.pop_frame();
        st.items.pop_back();  // the callee
        st.push_expr(std::move(e), callee.loc, h);
    }
};

template <>
struct action<g::index_suffix> {
    template <typename In>
    static void apply(const In&, State& st) {
        Item lhs;
        ExprPtr l = st.take_below(lhs);
        Frame items = st.take();
        auto e = make(ExprKind::Index, lhs.loc);
        uint32_t h = 1 + std::max(lhs.height, items[0].height);
        e->lhs = std::move(l);
        e->rhs = own(items[0]);
        st.pop_frame();
        st.items.pop_back();
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
        Item lhs;
        ExprPtr l = st.take_below(lhs);
        st.items.pop_back();
        auto e = make(ExprKind::Swizzle, lhs.loc);
        e->text = s.substr(0, n);
        e->lhs = std::move(l);
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
        Frame items = st.take();
        Loc loc = st.loc_at(in.begin());
        bool range = items.size != 0 && items.back().tag == Tag::RangeMark;
        if (range) --items.size;
        auto e = make(range ? ExprKind::Range : ExprKind::Vector, loc);
        uint32_t h = 1 + max_height(items);
        e->elems.reserve(range ? 3 : items.size);
        if (range) {
            e->elems.push_back(own(items.front()));
            e->elems.push_back(items.size == 3 ? own(items[1]) : nullptr);
            e->elems.push_back(own(items.back()));
        } else {
            for (auto& it : items) e->elems.push_back(own(it));
        }
        st.pop_frame();
        st.push_expr(std::move(e), loc, h);
    }
};

template <>
struct action<g::binding> {
    template <typename In>
    static void apply(const In&, State& st) {
        Frame items = st.take();
        Item it;
        it.tag = Tag::Binding;
        it.loc = items[0].loc;
        it.height = items[1].height;
        it.name = items[0].name;
        it.expr = std::exchange(items[1].expr, nullptr);
        st.pop_frame();
        st.items.push_back(it);
    }
};

std::vector<ForBinding> take_bindings(const Frame& items, size_t end) {
    std::vector<ForBinding> out;
    out.reserve(end);
    for (size_t i = 0; i < end; ++i)
        if (items[i].tag == Tag::Binding) out.push_back(ForBinding{items[i].loc, std::string(items[i].name), own(items[i])});
    return out;
}

template <>
struct action<g::for_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        Loc loc = st.loc_at(in.begin());
        auto e = make(ExprKind::For, loc);
        uint32_t h = 1 + max_height(items);
        e->body = own(items.back());
        e->bindings = take_bindings(items, items.size - 1);
        st.pop_frame();
        st.push_expr(std::move(e), loc, h);
    }
};

// elems = {cond, then, else}; else is null when absent.
template <>
struct action<g::if_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        Loc loc = st.loc_at(in.begin());
        auto e = make(ExprKind::If, loc);
        uint32_t h = 1 + max_height(items);
        e->elems.reserve(3);
        for (auto& it : items) e->elems.push_back(own(it));
        if (e->elems.size() == 2) e->elems.push_back(nullptr);
        st.pop_frame();
        st.push_expr(std::move(e), loc, h);
    }
};

template <>
struct action<g::target_if> : action<g::if_expr> {};
template <>
struct action<g::target_for> : action<g::for_expr> {};

template <>
struct action<g::field_expr> {
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        Loc loc = st.loc_at(in.begin());
        auto e = make(ExprKind::Field, loc);
        uint32_t h = 1 + max_height(items);
        size_t n = items.size;
        e->body = own(items[n - 1]);
        e->text = items[n - 2].name;
        e->args = take_args(items, 0, n - 2);
        st.pop_frame();
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
        Frame items = st.take();
        Loc loc = st.loc_at(in.begin());
        auto e = make(ExprKind::BlockExpr, loc);
        e->block = std::make_unique<Block>();
        e->block->loc = loc;
        uint32_t h = 2 + max_height(items);
        e->block->stmts.reserve(items.size);
        for (auto& it : items) {
            if (it.tag == Tag::Stmt)
                e->block->stmts.push_back(own_stmt(it));
            else
                e->block->result = own(it);  // only ever the last item
        }
        st.pop_frame();
        st.push_expr(std::move(e), loc, h);
    }
};

// A modifier followed by its target.
template <>
struct action<g::apply_target> {
    template <typename In>
    static void apply(const In&, State& st) {
        Item& target = st.take()[0];
        Item& mod = st.items[st.frame - 1];
        if (mod.expr->kind != ExprKind::Call && mod.expr->kind != ExprKind::Ident)
            throw CompileError(target.loc, "only a call or a name can be applied to a shape (is a ';' missing?)");
        Loc mod_loc = mod.loc;
        auto e = make(ExprKind::Apply, mod_loc);
        uint32_t h = 1 + std::max(mod.height, target.height);
        e->lhs = own(mod);
        e->rhs = own(target);
        st.pop_frame();
        st.items.pop_back();  // the modifier
        st.push_expr(std::move(e), mod_loc, h);
    }
};

// ---------------------------------------------------------------- statement actions

template <StmtKind Kind>
struct binding_stmt_action {  // let / var / assign: [name, value]
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        auto s = make_stmt(Kind, st.loc_at(in.begin()));
        s->name = items[0].name;
        s->name_loc = items[0].loc;
        s->value = own(items[1]);
        uint32_t h = items[1].height + 1;
        st.pop_frame();
        st.push_stmt(std::move(s), h);
    }
};
template <> struct action<g::let_stmt> : binding_stmt_action<StmtKind::Let> {};
template <> struct action<g::var_stmt> : binding_stmt_action<StmtKind::Var> {};
template <> struct action<g::assign_stmt> : binding_stmt_action<StmtKind::Assign> {};

struct param_action {  // [name, default?]
    template <typename In>
    static void apply(const In&, State& st) {
        Frame items = st.take();
        Item it;
        it.tag = Tag::Param;
        it.loc = items[0].loc;
        it.height = items.back().height;
        it.name = items[0].name;
        if (items.size == 2) it.expr = std::exchange(items[1].expr, nullptr);
        st.pop_frame();
        st.items.push_back(it);
    }
};
template <> struct action<g::expect_param> : param_action {};

template <>
struct action<g::def_stmt> {  // [name, params..., value]
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        auto s = make_stmt(StmtKind::Def, st.loc_at(in.begin()));
        s->name = items.front().name;
        s->name_loc = items.front().loc;
        s->params.reserve(items.size - 2);
        for (size_t i = 1; i + 1 < items.size; ++i)
            s->params.push_back(Param{items[i].loc, std::string(items[i].name), own(items[i])});
        s->value = own(items.back());
        uint32_t h = 1 + max_height(items);
        st.pop_frame();
        st.push_stmt(std::move(s), h);
    }
};

template <>
struct action<g::import_stmt> {
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        auto s = make_stmt(StmtKind::Import, st.loc_at(in.begin()));
        ExprPtr path = own(items[0]);
        s->name = std::move(path->text);
        s->name_loc = items[0].loc;
        st.pop_frame();
        st.push_stmt(std::move(s), 1);
    }
};

template <>
struct action<g::if_stmt> {  // [cond, then, else?]
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        auto s = make_stmt(StmtKind::If, st.loc_at(in.begin()));
        s->value = own(items[0]);
        s->then_branch = own_stmt(items[1]);
        if (items.size > 2) s->else_branch = own_stmt(items[2]);
        uint32_t h = 1 + max_height(items);
        st.pop_frame();
        st.push_stmt(std::move(s), h);
    }
};

template <>
struct action<g::for_stmt> {  // [bindings..., body]
    template <typename In>
    static void apply(const In& in, State& st) {
        Frame items = st.take();
        auto s = make_stmt(StmtKind::For, st.loc_at(in.begin()));
        uint32_t h = 1 + max_height(items);
        s->body = own_stmt(items.back());
        s->bindings = take_bindings(items, items.size - 1);
        st.pop_frame();
        st.push_stmt(std::move(s), h);
    }
};

template <>
struct action<g::empty_stmt> {
    template <typename In>
    static void apply(const In& in, State& st) {
        st.push_stmt(make_stmt(StmtKind::Empty, st.loc_at(in.begin())), 1);
    }
};

template <>
struct action<g::expr_stmt> {
    template <typename In>
    static void apply(const In&, State& st) {
        Frame items = st.take();
        auto s = make_stmt(StmtKind::Expr, items[0].loc);
        s->value = own(items[0]);
        uint32_t h = items[0].height + 1;
        st.pop_frame();
        st.push_stmt(std::move(s), h);
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

}  // namespace
}  // namespace sdfc::ast
