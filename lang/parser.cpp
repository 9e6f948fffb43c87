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
//
// The value stack is in parse_stack.hpp, the actions in parse_actions.hpp (headers so that
// this stays the one translation unit instantiating the grammar), the allocator of the
// nodes in node_pool.cpp; here are the control, the error positions and parse() itself.
#include <algorithm>
#include <cctype>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include <fmt/format.h>

#include "grammar/error_messages.hpp"
#include "grammar/sdf_grammar.hpp"
#include "lang/ast.hpp"
#include "lang/habits.hpp"
#include "lang/parse_stack.hpp"
#include "lang/parse_actions.hpp"

namespace sdfc::ast {
namespace {

namespace pegtl = tao::pegtl;
namespace g = sdfc::grammar;

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
            // (A top-level statement is no level of its own: N parentheses in it pass a limit of N.)
            if (st.depth > st.max_depth)
                throw CompileError(st.loc_at(in.current()), fmt::format("nesting deeper than {} levels ({})", st.max_depth,
                                               st.max_depth >= unsigned(ParseOptions::kMostNesting) ? "the most --max-nesting allows"
                                                                                                   : "raise it with --max-nesting"));
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

bool name_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// The name (letters, digits, '_') that starts at off; empty if none does.
std::string_view word_at(std::string_view t, size_t off) {
    size_t e = off;
    while (e < t.size() && name_char(t[e])) ++e;
    return t.substr(off, e - off);
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

// Whether a statement or a modifier's target may start after the token ending at `prev`
// (previous_token_end): the file's start, a ';', a '{', a '}' or a ')'.
bool target_after(std::string_view t, size_t prev) { return prev == 0 || std::strchr(";{})", t[prev - 1]) != nullptr; }

// Whether the whole word `w` starts somewhere in t[from, last] and is followed by `next`
// (right after it, or past blanks).
bool word_then(std::string_view t, size_t from, size_t last, std::string_view w, char next, bool past_blanks) {
    for (size_t e = t.find(w, from); e != std::string_view::npos && e <= last; e = t.find(w, e + 1)) {
        size_t k = e + w.size();
        while (past_blanks && k < t.size() && t[k] == ' ') ++k;
        if ((e == 0 || !name_char(t[e - 1])) && k < t.size() && t[k] == next) return true;
    }
    return false;
}

constexpr const char* kDebugModifiers =
    " (OpenSCAD's debug modifiers # % * ! have no use here: delete it, or comment the statement out)";

// A hint for OpenSCAD's (or GLSL's) syntax near a syntax error at `off`: a compound or
// component assignment, ++ and --, a line that starts with
// `include <` or `use <`, `each`, `import(`, a hex number, a debug modifier where a statement
// or a modifier's target starts, a `let (...)` expression.
std::string openscad_hint(std::string_view t, size_t off) {
    // GLSL's and C's: d += 2, d++, q.x = ... (an assignment sets a whole variable)
    if (off < t.size() && off > 0 && t[off] == '=' && (off + 1 >= t.size() || t[off + 1] != '=')) {
        const char op = t[off - 1];
        if (op == '+' || op == '-' || op == '*' || op == '/' || op == '%') {
            size_t e = off - 1;
            while (e > 0 && (t[e - 1] == ' ' || t[e - 1] == '\t')) --e;
            size_t b = e;
            while (b > 0 && name_char(t[b - 1])) --b;
            const std::string_view name = b < e ? t.substr(b, e - b) : std::string_view("x");
            return fmt::format(" (sdfc has no compound assignment: write `{0} = {0} {1} ...;`)", name, op);
        }
        size_t e = previous_token_end(t, off), b = e;
        while (b > 0 && name_char(t[b - 1])) --b;
        if (b > 1 && b < e && t[b - 1] == '.' && name_char(t[b - 2]))
            return " (a vector's components cannot be assigned one by one: give the whole vector, `q = [abs(q.x), q.y, q.z];`)";
    }
    if (off < t.size() && off > 0 && (t[off] == '+' || t[off] == '-') && t[off - 1] == t[off])
        return fmt::format(" (sdfc has no {0}{0}: write `i = i {0} 1;`)", t[off]);
    size_t start = off < t.size() ? off : previous_token_end(t, off);  // (the error may be at the end of the file)
    while (start > 0 && t[start - 1] != '\n') --start;
    while (start < t.size() && (t[start] == ' ' || t[start] == '\t')) ++start;
    const std::string_view first = word_at(t, start);
    size_t after = start + first.size();
    while (after < t.size() && t[after] == ' ') ++after;
    if ((first == "include" || first == "use") && after < t.size() && t[after] == '<') return habit_hint(first);
    const size_t w = previous_token_end(t, off);  // the word before the error
    size_t b = w;
    while (b > 0 && name_char(t[b - 1])) --b;
    if (off >= 4 && word_then(t, start, off - 4, "each", ' ', false)) return habit_hint("each");
    if (off < t.size() && t[off] == '(' && t.substr(b, w - b) == "import")
        return " (sdfc's `import \"file.sdf\";` reads a script's defs and lets: meshes such as .stl cannot be imported)";
    if (off < t.size() && (t[off] == 'x' || t[off] == 'X') && w > 0 && t[w - 1] == '0' && b + 1 == w)
        return " (sdfc has no hex numbers: write the number in decimal)";
    const bool stray_close = off + 1 < t.size() && t[off] == '*' && t[off + 1] == '/';  // (a comment's end)
    if (off < t.size() && (t[off] == '*' || t[off] == '%') && !stray_close && target_after(t, w)) return kDebugModifiers;
    // let (a = 2) ...: OpenSCAD's let expression, on the line up to the error (or at it)
    if (word_then(t, start, off, "let", '(', true))
        return " (sdfc's let is a statement, `let x = 2;`, whose name holds for the rest of its block; in a def, "
               "`def f(x) = { let y = x * 2; y + 1 };`)";
    return "";
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
                               : c == '$' && word_at(t, off + 1) == "t" ? " (OpenSCAD's $t is sdfc's `time`, in seconds: render --frames A:B --fps N)"
                               : c == '$'  ? " (OpenSCAD's $fn, $fa and $fs have no use here: sdfc's surfaces are exact; a 6-sided cylinder is hex_prism(h, r))"
                               : c == '#' && target_after(t, previous_token_end(t, off)) ? std::string(kDebugModifiers)
                                           : "";
            return CompileError(loc_at(f, off), fmt::format("unexpected character {}{}", what, hint));
        }
    }
    if (msg == g::error_message<g::expect_semi>) {
        // `function f(x) = ...;`, `float a = 1;`: the error's line starts with another
        // language's word and a name (statements start lines; a comment above may hold
        // any character, so the line, not the text since the last ';').
        size_t start = off;
        while (start > 0 && t[start - 1] != '\n') --start;
        while (start < off && (t[start] == ' ' || t[start] == '\t')) ++start;
        const std::string_view first = word_at(t, start);
        const size_t e = start + first.size();
        std::string hint = e < t.size() && t[e] == ' ' ? habit_hint(first) : "";
        if (hint.empty()) {
            // ... or a statement inside a block on that line: `field (p) -> { float d = ...; d }`
            size_t s = off;
            while (s > start && t[s - 1] != ';' && t[s - 1] != '{') --s;
            while (s < off && (t[s] == ' ' || t[s] == '\t')) ++s;
            const std::string_view w = s > start ? word_at(t, s) : std::string_view();
            if (!w.empty() && s + w.size() < t.size() && t[s + w.size()] == ' ') hint = habit_hint(w);
        }
        if (hint.empty()) hint = openscad_hint(t, off);
        return CompileError(loc_at(f, previous_token_end(t, off)), std::string(msg) + hint);
    }
    if (msg.rfind("expected a ", 0) == 0 && msg.find("name") != std::string::npos && off < t.size()) {
        const std::string_view word = word_at(t, off);
        if (is_keyword(word)) msg += fmt::format(" ('{}' is a keyword)", word);
    }
    msg += openscad_hint(t, off);
    return CompileError(loc_at(f, off), std::move(msg));
}

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
// goes. Bounded by max_thread_stack() (compiler/base/stack.cpp, smaller in sanitizer builds);
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
