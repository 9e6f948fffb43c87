// Builds the AST from the PEGTL grammar in grammar/sdf_grammar.hpp.
//
// How it works: every rule with an action reduces the items that its sub-rules pushed onto
// a value stack (State::items) into one item (an expression, a statement, an argument...).
// The control (base_control below) gives each such rule a frame, the stack size when the
// rule started, so an action knows which items are its own; postfix actions (call, index,
// swizzle, ternary tail, operator chains, modifier target) also take the one item just below
// their frame, the expression they extend. The control also
//   - truncates the stack when a rule fails, so a backtracking alternative leaves nothing,
//   - forces rewinding for error-point rules so errors point where the rule started,
//   - counts nesting (rules deriving from grammar::nesting) against the depth limit,
// and raises the messages of grammar/error_messages.hpp through tao::pegtl::must_if.
//
// Speed (see also the top of sdf_grammar.hpp): items are plain values (owning raw node
// pointers, names as views of the source), an action works on its items in place, the input
// tracks no line numbers (State::loc_at finds them in SourceFile::line_starts), and a
// frame is a local of the control's match, not a stack of its own.
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <memory>
#include <mutex>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <pthread.h>

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
// default, the iterable) until their parent node takes them. An item owns its `expr` and
// `stmt` (the State deletes what is left on the stack when parsing stops early); whoever
// takes them from an item takes ownership through own()/own_stmt(), which clear the item.
struct Item {
    Tag tag = Tag::Expr;
    BinOp op = BinOp::Add;
    uint32_t height = 1;    // height of the subtree
    Loc loc;                // first character (for an Expr: including enclosing parentheses)
    Expr* expr = nullptr;
    Stmt* stmt = nullptr;
    std::string_view name;  // a view of the source text
};

static_assert(std::is_trivially_copyable_v<Item> && std::is_trivially_destructible_v<Item>);

ExprPtr own(Item& it) { return ExprPtr(std::exchange(it.expr, nullptr)); }
StmtPtr own_stmt(Item& it) { return StmtPtr(std::exchange(it.stmt, nullptr)); }

// The items of the current rule (pushed since it started), in place on the stack.
struct Frame {
    Item* items;
    size_t size;
    Item& operator[](size_t i) const { return items[i]; }
    Item& front() const { return items[0]; }
    Item& back() const { return items[size - 1]; }
    Item* begin() const { return items; }
    Item* end() const { return items + size; }
};

// The value stack: a growable array of plain items (pushing and dropping are a store and a
// counter; dropping deletes nothing, see State::truncate).
class ItemStack {
    std::unique_ptr<Item[]> data_;
    size_t size_ = 0, cap_ = 0;

    [[gnu::noinline]] void grow() {
        size_t cap = cap_ ? 2 * cap_ : 256;
        std::unique_ptr<Item[]> d(new Item[cap]);
        std::copy(data_.get(), data_.get() + size_, d.get());
        data_ = std::move(d);
        cap_ = cap;
    }

public:
    size_t size() const { return size_; }
    Item* data() { return data_.get(); }
    Item* begin() { return data_.get(); }
    Item* end() { return data_.get() + size_; }
    Item& operator[](size_t i) { return data_[i]; }
    Item& back() { return data_[size_ - 1]; }
    [[gnu::always_inline]] Item& emplace_back() {
        if (size_ == cap_) grow();
        Item& it = data_[size_++];
        it = Item{};
        return it;
    }
    void push_back(const Item& it) { emplace_back() = it; }
    void pop_back() { --size_; }
    void resize_down(size_t n) { size_ = n; }
};

struct State {
    const SourceFile* file = nullptr;
    unsigned max_depth = 256;
    unsigned max_height = 1024;
    ItemStack items;
    size_t frame = 0;  // the current rule's frame: the stack size when it started
    unsigned depth = 0;
    // First attempt on the caller's stack: when the stack runs low before max_depth, give
    // up with StackTooSmall (parse() retries on a thread with a stack sized for max_depth).
    bool retry_on_low_stack = false;
    const char* block_end = nullptr;  // where the last block's `}` (and the space after it) ended

    // Lines are counted here, not by PEGTL (the input tracks no positions): `line` caches
    // the line of the last lookup, and lookups mostly move forward a little.
    const char* text = nullptr;
    const size_t* line_starts = nullptr;
    size_t line_count = 0;
    size_t line = 0;  // 0-based index into line_starts

    State() = default;
    State(const State&) = delete;
    State& operator=(const State&) = delete;
    ~State() { truncate(0); }

    bool just_after_block(const char* current) const { return current == block_end; }

    Loc loc_at(const char* p) {
        const size_t off = static_cast<size_t>(p - text);
        if (off < line_starts[line]) {
            line = static_cast<size_t>(std::upper_bound(line_starts, line_starts + line, off) - line_starts) - 1;
        } else {
            while (line + 1 < line_count && line_starts[line + 1] <= off) {
                if (line + 8 < line_count && line_starts[line + 8] <= off) {
                    line = static_cast<size_t>(std::upper_bound(line_starts + line + 8, line_starts + line_count, off) -
                                               line_starts) - 1;
                    break;
                }
                ++line;
            }
        }
        return Loc{file, static_cast<uint32_t>(line + 1), static_cast<uint32_t>(off - line_starts[line] + 1)};
    }

    // Drops the items above `n`, deleting the nodes they still own.
    void truncate(size_t n) {
        for (size_t i = n; i < items.size(); ++i) {
            delete items[i].expr;
            delete items[i].stmt;
        }
        items.resize_down(n);
    }

    // The current rule's items; the action takes all the nodes they own, then calls
    // pop_frame().
    Frame take() { return Frame{items.data() + frame, items.size() - frame}; }
    void pop_frame() {
        assert(std::all_of(items.begin() + frame, items.end(), [](const Item& it) { return !it.expr && !it.stmt; }));
        items.resize_down(frame);
    }
    // The item just below the current rule's frame (what a postfix rule extends), removed
    // from the stack; its expression is owned at once.
    ExprPtr take_below(Item& it) {
        Item& below = items[frame - 1];
        it = below;
        below.expr = nullptr;
        return own(it);
    }

    void check_height(uint32_t height, Loc loc) const {
        if (height > max_height)
            throw CompileError(loc, fmt::format("expression nested deeper than {} levels (split long chains of "
                                                "operators with `let`)",
                                                max_height));
    }
    void push_expr(ExprPtr e, Loc start, uint32_t height) {
        check_height(height, start);
        Item& it = items.emplace_back();
        it.loc = start;
        it.height = height;
        it.expr = e.release();
    }
    void push_stmt(StmtPtr s, uint32_t height) {
        if (height > max_height)
            throw CompileError(s->loc, fmt::format("statement nested deeper than {} levels (raise it with --max-nesting)", max_height));
        Item& it = items.emplace_back();
        it.tag = Tag::Stmt;
        it.loc = s->loc;
        it.height = height;
        it.stmt = s.release();
    }
    void push_mark(Tag t) { items.emplace_back().tag = t; }
};

ExprPtr make(ExprKind k, Loc loc) {
    ExprPtr e(new Expr);
    e->kind = k;
    e->loc = loc;
    return e;
}

StmtPtr make_stmt(StmtKind k, Loc loc) {
    StmtPtr s(new Stmt);
    s->kind = k;
    s->loc = loc;
    return s;
}

uint32_t max_height(const Frame& items) {
    uint32_t h = 0;
    for (const auto& it : items) h = std::max(h, it.height);
    return h;
}

// ---------------------------------------------------------------- actions

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

// ---------------------------------------------------------------- control

// Whether matching Rule may push items: it, or a rule below it, has an action. Recursion
// (the grammar is recursive) is cut off at a depth, answering yes.
template <template <typename...> class Action, typename Rule, int Depth>
struct may_push;
template <template <typename...> class Action, typename Subs, int Depth>
struct any_may_push;
template <template <typename...> class Action, typename... Subs, int Depth>
struct any_may_push<Action, pegtl::type_list<Subs...>, Depth> {
    static constexpr bool value = (may_push<Action, Subs, Depth>::value || ...);
};
template <template <typename...> class Action, typename Rule, int Depth>
struct may_push {
    static constexpr bool value = [] {
        if constexpr (!std::is_base_of_v<pegtl::nothing<Rule>, Action<Rule>> || Depth >= 8)
            return true;
        else
            return any_may_push<Action, typename Rule::subs_t, Depth + 1>::value;
    }();
};

// Thrown (and caught in parse()) when the caller's stack runs out before the depth limit.
struct StackTooSmall {};

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
        // Most rule attempts (tokens, characters, lookaheads) push nothing: no bookkeeping.
        constexpr bool tracked = A == pegtl::apply_mode::action && may_push<Action, Rule, 0>::value;

        struct DepthGuard {
            unsigned* depth;
            ~DepthGuard() {
                if (depth) --*depth;
            }
        } guard{nullptr};
        if constexpr (nests) {
            if (st.depth >= st.max_depth)
                throw CompileError(st.loc_at(in.current()), fmt::format("nesting deeper than {} levels (raise it with --max-nesting)", st.max_depth));
            // Whatever max_depth was raised to, stop before the C++ stack runs out.
            if (stack_nearly_exhausted()) {
                if (st.retry_on_low_stack) throw StackTooSmall{};
                check_stack(st.loc_at(in.current()));
            }
            ++st.depth;
            guard.depth = &st.depth;
        }
        if constexpr (!tracked) {
            return pegtl::normal<Rule>::template match<A, mode, Action, Control>(in, st);
        } else {
            const size_t mark = st.items.size();
            size_t outer_frame = 0;
            if constexpr (framed) {
                outer_frame = st.frame;
                st.frame = mark;
            }
            const bool ok = pegtl::normal<Rule>::template match<A, mode, Action, Control>(in, st);
            if constexpr (framed) st.frame = outer_frame;
            if (!ok && st.items.size() > mark) st.truncate(mark);
            return ok;
        }
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

// ---------------------------------------------------------------- node allocation

// Expr and Stmt nodes (ast.hpp) come from per-thread pools of same-size slots: a pool hands
// out freed slots last-in first-out (kept in an array, so reuse reads no freed memory), else
// the next slot of its current chunk. Memory is never given back to the system, so parsing
// again reuses it without page faults (first-touch faults dominate a big script's parse).
// A thread that exits leaves its slots in a global depot for other threads; all chunks are
// on a global list, so leak checkers see them as reachable. Under AddressSanitizer nodes use
// the ordinary heap, so it still finds use-after-free.
#if defined(__SANITIZE_ADDRESS__)
#define SDFC_NODE_POOL 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SDFC_NODE_POOL 0
#endif
#endif
#ifndef SDFC_NODE_POOL
#define SDFC_NODE_POOL 1
#endif

#if SDFC_NODE_POOL
struct PoolChunk {
    PoolChunk* next;
};
constinit std::atomic<PoolChunk*> all_chunks{nullptr};

// A thread's pool for one slot size. Plain data (so it stays usable while the thread's other
// thread_locals are destroyed); PoolExit hands its slots over to the depot at thread exit.
template <size_t Size>
struct NodePool {
    static constexpr size_t kHeader = alignof(std::max_align_t);
    static_assert(sizeof(PoolChunk) <= kHeader && Size % alignof(std::max_align_t) == 0);
    static constexpr size_t kFirstChunk = 64 << 10, kMaxChunk = 1 << 20;

    void** free = nullptr;  // freed slots, reused first-in first-out: free[head, count); malloc'ed
    size_t head = 0, count = 0, cap = 0;
    char* next = nullptr;   // the unused rest of the current chunk
    char* end = nullptr;
    size_t chunk_bytes = kFirstChunk;
    bool exited = false;    // after thread exit, slots come from and go to the depot

    // Slots of exited threads. Never destroyed: threads (and static destructors) may free
    // nodes after main() returned.
    struct Depot {
        std::mutex mutex;
        std::vector<void*> slots;
    };
    static Depot& depot() {
        static Depot* d = new Depot;
        return *d;
    }

    void* get() {
        if (head != count) return take_free();
        if (next != end) return std::exchange(next, next + Size);
        return refill();
    }
    // Oldest first: a tree is freed in about the order it was allocated, so the next parse
    // gets its slots in about address order too.
    void* take_free() {
        void* p = free[head++];
        if (head == count) head = count = 0;
        return p;
    }
    void put(void* p) noexcept {
        if (count == cap && head != 0) {
            std::memmove(static_cast<void*>(free), static_cast<void*>(free + head), (count - head) * sizeof(void*));
            count -= head;
            head = 0;
        }
        if (count == cap && !grow()) {
            to_depot(p);
            return;
        }
        free[count++] = p;
    }

    bool grow() noexcept {
        if (exited) return false;
        size_t n = cap ? 2 * cap : 4096;
        void* f = std::realloc(static_cast<void*>(free), n * sizeof(void*));
        if (!f) return false;
        free = static_cast<void**>(f);
        cap = n;
        return true;
    }
    static void to_depot(void* p) noexcept {
        Depot& d = depot();
        std::lock_guard<std::mutex> lock(d.mutex);
        try {
            d.slots.push_back(p);
        } catch (...) {  // out of memory: the slot is lost, not the program
        }
    }
    void* refill();
    void hand_over() noexcept {
        Depot& d = depot();
        std::lock_guard<std::mutex> lock(d.mutex);
        try {
            d.slots.insert(d.slots.end(), free + head, free + count);
            for (; next != end; next += Size) d.slots.push_back(next);
        } catch (...) {
        }
        std::free(static_cast<void*>(free));
        free = nullptr;
        head = count = cap = 0;
        next = end = nullptr;
        exited = true;
    }
};

constexpr size_t slot_size(size_t n) { return (n + 15) / 16 * 16; }
using ExprPool = NodePool<slot_size(sizeof(Expr))>;
using StmtPool = NodePool<slot_size(sizeof(Stmt))>;
thread_local constinit ExprPool expr_pool;
thread_local constinit StmtPool stmt_pool;

struct PoolExit {
    ~PoolExit() {
        expr_pool.hand_over();
        stmt_pool.hand_over();
    }
};
thread_local PoolExit pool_exit;

template <size_t Size>
void* NodePool<Size>::refill() {
    static_cast<void>(&pool_exit);  // registers the hand-over at this thread's exit
    {
        Depot& d = depot();
        std::lock_guard<std::mutex> lock(d.mutex);
        if (!d.slots.empty()) {
            if (exited) {
                void* p = d.slots.back();
                d.slots.pop_back();
                return p;
            }
            while (!d.slots.empty() && (count < cap || grow()) && count < 4096) {
                free[count++] = d.slots.back();
                d.slots.pop_back();
            }
        }
    }
    if (head != count) return take_free();
    if (exited) return ::operator new(Size);  // a slot of its own, given to the depot when freed
    char* mem = static_cast<char*>(::operator new(chunk_bytes));
    auto* chunk = reinterpret_cast<PoolChunk*>(mem);
    chunk->next = all_chunks.load(std::memory_order_relaxed);
    while (!all_chunks.compare_exchange_weak(chunk->next, chunk, std::memory_order_release, std::memory_order_relaxed)) {
    }
    next = mem + kHeader;
    end = next + (chunk_bytes - kHeader) / Size * Size;
    chunk_bytes = std::min(2 * chunk_bytes, kMaxChunk);
    return std::exchange(next, next + Size);
}
#endif

}  // namespace

#if SDFC_NODE_POOL
void* Expr::operator new(std::size_t size) { return size == sizeof(Expr) ? expr_pool.get() : ::operator new(size); }
void Expr::operator delete(void* p, std::size_t size) noexcept {
    if (!p) return;
    if (size == sizeof(Expr))
        expr_pool.put(p);
    else
        ::operator delete(p);
}
void* Stmt::operator new(std::size_t size) { return size == sizeof(Stmt) ? stmt_pool.get() : ::operator new(size); }
void Stmt::operator delete(void* p, std::size_t size) noexcept {
    if (!p) return;
    if (size == sizeof(Stmt))
        stmt_pool.put(p);
    else
        ::operator delete(p);
}
#else
void* Expr::operator new(std::size_t size) { return ::operator new(size); }
void Expr::operator delete(void* p, std::size_t) noexcept { ::operator delete(p); }
void* Stmt::operator new(std::size_t size) { return ::operator new(size); }
void Stmt::operator delete(void* p, std::size_t) noexcept { ::operator delete(p); }
#endif

namespace {

std::unique_ptr<Module> parse_on_this_stack(const SourceFile& file, unsigned max_depth, bool retry_on_low_stack) {
    State st;
    st.file = &file;
    st.max_depth = max_depth;
    st.retry_on_low_stack = retry_on_low_stack;
    // Operator chains make trees taller than their nesting; later stages recurse over the
    // tree, so its height is bounded too.
    st.max_height = std::max(4 * st.max_depth, 64u);
    st.text = file.text.data();
    st.line_starts = file.line_starts.data();
    st.line_count = file.line_starts.size();
    pegtl::memory_input<pegtl::tracking_mode::lazy, pegtl::eol::lf_crlf, const char*> in(
        file.text.data(), file.text.size(), file.path.c_str());
    try {
        pegtl::parse<g::grammar, action, control>(in, st);
    } catch (const pegtl::parse_error& e) {
        const auto& p = e.positions().front();
        throw syntax_error(file, p.byte, std::string(e.message()));
    }
    auto m = std::make_unique<Module>();
    m->file = &file;
    m->stmts.reserve(st.items.size());
    for (auto& it : st.items) m->stmts.push_back(own_stmt(it));
    return m;
}

// The stack a parse on its own thread gets: this much per nesting level, far more than any
// build uses (a level is a few dozen PEGTL frames: about 1 KB in Release, 8-12 KB under
// AddressSanitizer), plus a base. It is address space, touched only as deep as the input
// goes. Bounded by max_thread_stack() (compiler/base/source.cpp, smaller in sanitizer builds);
// beyond it the stack guard reports the input as too deeply nested.
constexpr size_t kStackPerLevel = 64u << 10;
constexpr size_t kStackBase = 8u << 20;

struct ParseJob {
    const SourceFile* file;
    unsigned max_depth;
    std::unique_ptr<Module> module;
    std::exception_ptr error;
};

// Parses on a new thread whose stack fits max_depth levels; false when no such thread can
// be made (the caller then parses on its own stack, stopped by the stack guard).
bool parse_on_big_stack(ParseJob& job) {
    const size_t want = std::min(kStackBase + size_t(job.max_depth) * kStackPerLevel, max_thread_stack());
    return run_on_new_stack(want, [&job] {
        try {
            job.module = parse_on_this_stack(*job.file, job.max_depth, false);
        } catch (...) {
            job.error = std::current_exception();
        }
    });
}

}  // namespace

// Parsing recurses once per nesting level (parentheses, blocks, modifiers, operands), a few
// dozen frames each. The caller's stack (8 MB for the main thread, often less for others)
// may run out before max_nesting, the sooner in sanitizer builds: then the parse starts
// again on a thread with a stack sized for max_nesting, so the depth limit, not the build or
// the thread, decides where deep input stops, always as "nesting deeper than N levels".
// (That thread's nodes come from its own pool; freed later by the caller, they go to the
// caller's pool, which reuses them: NodePool allows any thread to free a node.)
std::unique_ptr<Module> parse(const SourceFile& file, const ParseOptions& opts) {
    const auto max_depth = static_cast<unsigned>(std::max(opts.max_nesting, 1));
    try {
        return parse_on_this_stack(file, max_depth, true);
    } catch (const StackTooSmall&) {
    }
    ParseJob job{&file, max_depth, nullptr, nullptr};
    if (!parse_on_big_stack(job)) return parse_on_this_stack(file, max_depth, false);
    if (job.error) std::rethrow_exception(job.error);
    return std::move(job.module);
}

}  // namespace sdfc::ast
