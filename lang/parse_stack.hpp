// The parser's value stack: the items that rules with actions push (expressions,
// statements, arguments, names...), the frame of the rule being matched, and the
// line lookup for locations. Private to lang/parser.cpp, the one translation unit that
// instantiates the grammar (hence the unnamed namespace); see the top of parser.cpp.
#pragma once
#include <algorithm>
#include <cassert>
#include <cstdint>
#include <memory>
#include <string_view>
#include <type_traits>
#include <utility>

#include <fmt/format.h>

#include "lang/ast.hpp"

namespace sdfc::ast {
namespace {

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
            throw CompileError(loc, fmt::format("expression nested deeper than {} levels: each operator of a chain "
                                                "is a level (split the chain with `let`, or raise the limit, 4 x "
                                                "--max-nesting)",
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

}  // namespace
}  // namespace sdfc::ast
