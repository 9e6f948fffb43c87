// The grammar of .sdf scripts (LANGUAGE.md sections 2-7) as PEGTL 3 rules, and nothing
// else: the actions that build the AST live in lang/parse_actions.hpp (compiled only in
// lang/parser.cpp), the error messages in grammar/error_messages.hpp. Include this header
// only from those files (and the grammar's own test): PEGTL templates are heavy to compile.
//
// Conventions
// - Every token rule consumes the whitespace and comments after it (`sp`), so each rule
//   starts on the first byte of its first token and that position is the node's Loc.
// - Error points are rules that carry a message in error_messages.hpp (many are named
//   `expect_*`, `missing_*`, `*_close`) and raise it as soon as they fail (must_if style).
//   They appear only where failing means the script is wrong, never inside an alternative
//   that may legitimately fail. Error points have no actions: one that names a rule with
//   an action wraps it as `seq<rule>` (not by deriving from it), so the action still runs
//   and the error is reported where the rule started.
// - Rules deriving from `nesting` are the points where the grammar recurses; the parser
//   counts them and stops at a depth limit, so deep input is an error, not a stack overflow.
// - Lookaheads (`at`, `not_at`) decide between alternatives before any action-bearing rule
//   runs, so the parser almost never has to undo work.
// - Speed: every rule attempt costs a call through the control (and a rule with an action
//   costs more), so where a rule is tried after almost every token (operators, postfix
//   operators, modifier targets, keyword statements) a one-character guard (`when<>`,
//   `at<>`) comes first; each guard is implied by the rule it guards, so it never changes
//   what matches. A few rules are hand-written (sp, any_key, when), each analyzed as the
//   plain rule it stands for. Budget: a 400 KB script (10,000 statements) parses in about
//   10 ms; measure before and after changing a rule on that path.
#pragma once
#include <algorithm>
#include <cstddef>

#include <tao/pegtl.hpp>
#include <tao/pegtl/contrib/analyze_traits.hpp>

namespace sdfc::grammar {

using namespace tao::pegtl;

// Marks a recursion point of the grammar (see the depth limit in lang/parser.cpp).
struct nesting {};

// seq<at<Guard>, Rule> for a one-character Guard (a one<> or ranges<>): Rule, tried only when
// the next character passes Guard. A cheap guard for a rule that cannot match otherwise.
template <typename Guard, typename Rule>
struct when {
    using rule_t = when;
    using subs_t = type_list<Guard, Rule>;
    template <apply_mode A, rewind_mode M, template <typename...> class Action, template <typename...> class Control,
              typename ParseInput, typename... States>
    static bool match(ParseInput& in, States&&... st) {
        return !in.empty() && Guard::test(in.peek_char()) &&
               Control<Rule>::template match<A, M, Action, Control>(in, st...);
    }
};

// ---------------------------------------------------------------------------------------
// Lexical: whitespace and comments

// A fixed string, matched byte by byte (cheaper than string<>'s memcmp for 2-6 bytes).
template <char... C>
struct lit : seq<one<C>...> {};
struct line_comment : seq<two<'/'>, until<eolf>> {};
struct block_comment_body : seq<one<'/'>, one<'*'>, until<lit<'*', '/'>>> {};  // "unterminated comment"
struct block_comment : seq<at<one<'/'>, one<'*'>>, block_comment_body> {};

// Whitespace and comments, after every token:  star<sor<space, line_comment, block_comment>>.
// Blanks and line comments are skipped in a loop here; block comments go through their rule
// (which reports an unterminated one).
struct sp {
    using rule_t = sp;
    using subs_t = type_list<sor<space, line_comment, block_comment>>;
    template <apply_mode A, rewind_mode M, template <typename...> class Action, template <typename...> class Control,
              typename ParseInput, typename... States>
    static bool match(ParseInput& in, States&&... st) {
        for (;;) {
            const char* p = in.current();
            const char* const e = in.end();
            if (p == e || (static_cast<unsigned char>(*p) > ' ' && *p != '/')) return true;  // the usual case
            while (p != e && (*p == ' ' || *p == '\n' || *p == '\t' || *p == '\r' || *p == '\v' || *p == '\f')) ++p;
            if (e - p >= 2 && p[0] == '/' && p[1] == '/') {  // until<eolf>: to the next '\n' (ending "\n" or "\r\n")
                p += 2;
                while (p != e && *p != '\n') ++p;
                if (p != e) ++p;
                in.bump(static_cast<std::size_t>(p - in.current()));
                continue;
            }
            in.bump(static_cast<std::size_t>(p - in.current()));
            if (e - p >= 2 && p[0] == '/' && p[1] == '*') {
                if (!Control<block_comment>::template match<A, M, Action, Control>(in, st...)) return true;
                continue;
            }
            return true;
        }
    }
};

template <char... C>
struct sym : seq<one<C...>, sp> {};
template <char... C>
struct op : seq<lit<C...>, sp> {};

// Identifiers and keywords. A keyword must not be the prefix of a longer name (`letter`).
template <char... C>
struct key : seq<lit<C...>, not_at<identifier_other>> {
    static constexpr char word[] = {C...};
};
// Any of the keywords Keys (each a key<>) as a whole word: sor<Keys...>, in one pass over
// the word instead of one try per keyword (every name is checked against all of them).
template <typename... Keys>
struct any_key {
    using rule_t = any_key;
    using subs_t = type_list<Keys...>;
    static constexpr std::size_t longest = std::max({sizeof(Keys::word)...});
    static constexpr bool is_word_char(char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    }
    template <typename ParseInput>
    static bool match(ParseInput& in) {
        const char* const b = in.current();
        const std::size_t avail = in.size(longest + 1);
        if (avail == 0 || !((b[0] == Keys::word[0]) || ...)) return false;
        std::size_t n = 0;
        while (n < avail && n <= longest && is_word_char(b[n])) ++n;
        if (n > longest) return false;  // a longer word
        const bool found = ((n == sizeof(Keys::word) && std::equal(b, b + n, Keys::word)) || ...);
        if (found) in.bump(n);
        return found;
    }
};
struct kw_let : key<'l', 'e', 't'> {};
struct kw_def : key<'d', 'e', 'f'> {};
struct kw_field : key<'f', 'i', 'e', 'l', 'd'> {};
struct kw_var : key<'v', 'a', 'r'> {};
struct kw_for : key<'f', 'o', 'r'> {};
struct kw_if : key<'i', 'f'> {};
struct kw_else : key<'e', 'l', 's', 'e'> {};
struct kw_import : key<'i', 'm', 'p', 'o', 'r', 't'> {};
struct kw_true : key<'t', 'r', 'u', 'e'> {};
struct kw_false : key<'f', 'a', 'l', 's', 'e'> {};
struct keyword : any_key<kw_let, kw_def, kw_field, kw_var, kw_for, kw_if, kw_else, kw_import, kw_true, kw_false> {};
struct name : seq<not_at<keyword>, identifier> {};

template <typename Kw>
struct kw : seq<Kw, sp> {};

// Numbers: 1  1.5  .5  1e-3  2.  (no sign: `-` is the unary operator)
struct digits : plus<digit> {};
struct exponent_digits : digits {};  // "expected digits in the number's exponent"
struct exponent : seq<one<'e', 'E'>, opt<one<'+', '-'>>, exponent_digits> {};
struct number_lit : seq<sor<seq<digits, opt<one<'.'>, opt<digits>>>, seq<one<'.'>, digits>>, opt<exponent>> {};

// Strings: "..." with \" \\ \n \t; a string ends at the end of its line.
struct escape_seq : seq<one<'\\'>, one<'"', '\\', 'n', 't'>> {};  // "unknown escape sequence"
struct escape : seq<at<one<'\\'>>, escape_seq> {};
struct string_char : sor<escape, not_one<'"', '\\', '\n', '\r'>> {};
struct string_text : seq<one<'"'>, until<one<'"'>, string_char>> {};
struct string_body : seq<string_text> {};  // "unterminated string"
struct string_lit : seq<at<one<'"'>>, string_body> {};

// ---------------------------------------------------------------------------------------
// Punctuation and operators
struct comma : sym<','> {};
struct semi : sym<';'> {};
struct colon : sym<':'> {};
struct lparen : sym<'('> {};
struct lbracket : sym<'['> {};
struct lbrace : sym<'{'> {};
struct equals : seq<one<'='>, not_at<one<'='>>, sp> {};
struct arrow : op<'-', '>'> {};
struct question : sym<'?'> {};

struct op_or : op<'|', '|'> {};
struct op_and : op<'&', '&'> {};
struct op_eq : op<'=', '='> {};
struct op_ne : op<'!', '='> {};
struct op_le : op<'<', '='> {};
struct op_ge : op<'>', '='> {};
struct op_lt : sym<'<'> {};
struct op_gt : sym<'>'> {};
struct op_add : sym<'+'> {};
struct op_sub : seq<one<'-'>, not_at<one<'>'>>, sp> {};
struct op_mul : sym<'*'> {};
struct op_div : sym<'/'> {};
struct op_mod : sym<'%'> {};
struct op_neg : seq<one<'-'>, not_at<one<'>'>>, sp> {};
struct op_not : seq<one<'!'>, not_at<one<'='>>, sp> {};

// Error points for punctuation (messages in error_messages.hpp).
struct expect_rparen : sym<')'> {};
struct expect_rbracket : sym<']'> {};
struct expect_equals : equals {};
struct expect_semi : semi {};
struct missing_semi : failure {};

// ---------------------------------------------------------------------------------------
// Expressions, loosest first:  ?:  ||  &&  comparisons  + -  * / %  unary - !  postfix
struct expression;
struct statement;
struct block_statement;

// Any expression; recursion goes through here.
struct ternary;
struct expression : seq<ternary>, nesting {};
struct expect_expr : expression {};     // "expected an expression"
struct value_expr : expression {};      // after '=': "expected an expression after '='"

// Arguments: positional and named (`name = value`), mixed, trailing comma allowed.
struct arg_name : name {};
struct named_arg : seq<at<name, sp, equals>, arg_name, sp, equals, value_expr> {};
struct arg : sor<named_arg, expression> {};
struct call_args : seq<lparen, opt<list_tail<arg, comma>>, expect_rparen> {};

// Blocks `{ statements [result] }`. The closing brace records where it ended, so that a
// statement ending in a block needs no ';' (see after_block).
struct rbrace : seq<one<'}'>, sp> {};
struct block_close : seq<rbrace> {};  // "expected '}'"
struct block : seq<lbrace, star<block_statement>, block_close> {};

// `{ ... }` may end an expression statement without ';'. True exactly when the previous
// token is the `}` of a block; the parse state remembers where the last block ended.
// The state must provide `bool just_after_block(const char* current)`.
struct after_block {
    using rule_t = after_block;
    using subs_t = type_list<>;
    template <apply_mode, rewind_mode, template <typename...> class Action, template <typename...> class Control,
              typename ParseInput, typename State>
    static bool match(ParseInput& in, State& st) {
        return st.just_after_block(in.current());
    }
};

// Postfix operators: call f(...), index v[i], swizzle v.xyz (`.5` is not a swizzle).
struct index_expr : expression {};  // "expected an expression"
struct call_suffix : call_args {};
struct index_suffix : seq<lbracket, index_expr, expect_rbracket> {};
struct swizzle_letters : identifier {};  // "expected swizzle letters"
struct swizzle_suffix : seq<one<'.'>, not_at<digit>, swizzle_letters, sp> {};
struct postfix_op : sor<call_suffix, index_suffix, swizzle_suffix> {};
struct postfix_ops : star<when<one<'(', '[', '.'>, postfix_op>> {};

// Primaries that may take postfix operators.
struct number : seq<number_lit, sp> {};
struct string_expr : seq<string_lit, sp> {};
struct true_lit : kw<kw_true> {};
struct false_lit : kw<kw_false> {};
struct ident_name : name {};
struct ident_expr : seq<ident_name, sp> {};
struct paren_expr : seq<lparen, expect_expr, expect_rparen> {};

// [a, b, c] and [] (vectors), [a : b] and [a : step : b] (ranges).
struct vector_close : sym<']'> {};  // "expected ',' or ']'"
struct range_close : sym<']'> {};   // "expected ']' to close the range"
struct range_tail : seq<colon, expect_expr, opt<colon, expect_expr>, range_close> {};
struct vector_tail : seq<star<comma, expression>, opt<comma>, vector_close> {};
struct empty_vector : sym<']'> {};
struct bracket_expr : seq<lbracket, sor<empty_vector, seq<expression, sor<range_tail, vector_tail>>>> {};

struct simple_primary : sor<number, string_expr, true_lit, false_lit, paren_expr, bracket_expr> {};

// `for (i = r, j = s) target`, shared with the for statement.
struct loop_var : name {};
struct binding_name : seq<loop_var> {};  // "expected a loop variable name"
struct for_iterable : expression {};  // "expected what to iterate over"
struct binding : seq<binding_name, sp, expect_equals, for_iterable> {};
struct for_lparen : sym<'('> {};        // "expected '(' after 'for'"
struct for_rparen : sym<')'> {};        // "expected ')' after the loop variables"
struct for_header : seq<kw<kw_for>, for_lparen, binding, star<comma, binding>, for_rparen> {};

// `if (cond) ...`, shared with the if statement.
struct if_lparen : sym<'('> {};      // "expected '(' after 'if'"
struct condition : expression {};    // "expected a condition"
struct if_rparen : sym<')'> {};      // "expected ')' after the condition"
struct if_header : seq<kw<kw_if>, if_lparen, condition, if_rparen> {};

// Expressions that begin with a keyword or a brace and extend to the right as far as they
// can; they take no postfix operators.
struct branch_expr : expression {};  // "expected an expression"
struct if_expr : seq<if_header, branch_expr, opt<kw<kw_else>, branch_expr>> {};
struct for_expr : seq<for_header, branch_expr> {};

// field (p) -> body   and   field(bound = 2) (p) -> body
struct field_param_name : name {};
struct field_param_ahead : seq<one<'('>, sp, name, sp, one<')'>, sp, not_at<one<'('>>> {};
struct field_args : call_args {};
struct field_param : seq<lparen, field_param_name, sp, expect_rparen> {};  // "expected '(' and the field's parameter"
struct expect_arrow : arrow {};      // "expected '->' after the field's parameter"
struct field_body : expression {};   // "expected an expression after '->'"
struct field_expr : seq<kw<kw_field>, opt<not_at<field_param_ahead>, field_args>, field_param, expect_arrow, field_body> {};

struct brace_primary : sor<block, field_expr, if_expr, for_expr> {};

// Modifier application, OpenSCAD style: a call or name directly followed by a target
// (a shape expression, a block, a for or an if) applies to it; nests to the right. A target
// that begins with a name is a whole expression, so `translate(v) k > 1 ? a : b` moves the
// conditional's shape, not k.
// (The guard comes after the nesting check: the depth limit applies to every attempt.)
struct ident_postfix;
struct target_start : sor<one<'{'>, identifier_first, digit> {};
// An `if` target, or one inside a `for` target, may also end its first branch with ';'
// before `else`, as OpenSCAD's `translate(v) if (c) a(); else b();` does (the else goes
// with the nearest if).
struct semi_else : seq<semi, kw<kw_else>> {};
struct target_if;
struct target_for;
struct target_branch : sor<target_if, target_for, branch_expr>, nesting {};
struct target_if : seq<if_header, target_branch, opt<sor<kw<kw_else>, semi_else>, target_branch>> {};
struct target_for : seq<for_header, target_branch> {};
struct apply_target : seq<at<target_start>, sor<block, target_for, target_if, field_expr, ternary>>, nesting {};
struct ident_postfix : seq<at<identifier_first>, ident_expr, postfix_ops, opt<apply_target>> {};
struct other_postfix : seq<simple_primary, postfix_ops> {};
struct postfix_expr : sor<ident_postfix, other_postfix, brace_primary> {};

struct unary;
struct neg_operand : seq<unary>, nesting {};  // "expected an expression after '-'"
struct not_operand : seq<unary>, nesting {};  // "expected an expression after '!'"
struct neg_expr : seq<op_neg, neg_operand> {};
struct not_expr : seq<op_not, not_operand> {};
struct unary : sor<when<one<'-', '!'>, sor<neg_expr, not_expr>>, postfix_expr> {};

// Binary levels: left-associative chains `operand (op operand)*`. The `*_chain` rules (all
// of a level's operators and right operands, folded onto the left operand by the parser)
// are tried only when an operator of their level is next.
struct mul_rhs : unary {};  // "expected an expression after the operator" (and below)
struct mul_chain : plus<sor<op_mul, op_div, op_mod>, mul_rhs> {};
struct mul_level : seq<unary, opt<when<one<'*', '/', '%'>, mul_chain>>> {};
struct add_rhs : seq<mul_level> {};
struct add_chain : plus<sor<op_add, op_sub>, add_rhs> {};
struct add_level : seq<mul_level, opt<when<one<'+', '-'>, add_chain>>> {};
struct cmp_rhs : seq<add_level> {};
struct cmp_chain : plus<sor<op_eq, op_ne, op_le, op_ge, op_lt, op_gt>, cmp_rhs> {};
struct cmp_level : seq<add_level, opt<when<one<'=', '!', '<', '>'>, cmp_chain>>> {};
struct and_rhs : seq<cmp_level> {};
struct and_chain : plus<op_and, and_rhs> {};
struct and_level : seq<cmp_level, opt<when<one<'&'>, and_chain>>> {};
struct or_rhs : seq<and_level> {};
struct or_chain : plus<op_or, or_rhs> {};
struct or_level : seq<and_level, opt<when<one<'|'>, or_chain>>> {};

// cond ? a : b, right-associative (the else branch is a whole expression).
struct ternary_then : expression {};  // "expected an expression after '?'"
struct ternary_colon : sym<':'> {};   // "expected ':' ..."
struct ternary_else : expression {};  // "expected an expression after ':'"
struct ternary_tail : seq<question, ternary_then, ternary_colon, ternary_else> {};
struct ternary : seq<or_level, opt<when<one<'?'>, ternary_tail>>> {};

// ---------------------------------------------------------------------------------------
// Statements
struct decl_name : name {};
struct let_name : seq<decl_name> {};  // "expected a name after 'let'"
struct var_name : seq<decl_name> {};  // "expected a name after 'var'"
struct def_name : seq<decl_name> {};  // "expected a name after 'def'"
struct let_stmt : seq<kw<kw_let>, let_name, sp, expect_equals, value_expr, expect_semi> {};
struct var_stmt : seq<kw<kw_var>, var_name, sp, expect_equals, value_expr, expect_semi> {};
struct assign_stmt : seq<at<name, sp, equals>, decl_name, sp, equals, value_expr, expect_semi> {};

// def name(a, b = 1) = expr;   def name(a) { ... }
struct param_name : name {};
struct expect_param_name : seq<param_name> {};  // "expected a parameter name"
struct param_default : seq<equals, value_expr> {};
struct expect_param : seq<expect_param_name, sp, opt<param_default>> {};
struct def_lparen : sym<'('> {};   // "expected '(' after the function name"
struct params_close : sym<')'> {}; // "expected ')' after the parameters"
struct def_params
    : seq<def_lparen, opt<not_at<one<')'>>, expect_param, star<comma, sor<at<one<')'>>, expect_param>>>, params_close> {};
struct missing_def_body : failure {};  // "expected '=' or '{' after the parameters"
struct def_body : sor<seq<equals, value_expr, expect_semi>, block, missing_def_body> {};
struct def_stmt : seq<kw<kw_def>, def_name, sp, def_params, def_body> {};

struct import_path : seq<string_lit, sp> {};  // "expected a path string after 'import'"
struct import_stmt : seq<kw<kw_import>, import_path, expect_semi> {};

struct body_stmt : seq<statement> {};  // "expected a statement"
struct if_stmt : seq<if_header, body_stmt, opt<kw<kw_else>, body_stmt>> {};
struct for_stmt : seq<for_header, body_stmt> {};
struct empty_stmt : semi {};

// An expression statement ends with ';', or needs none when it ends with a block.
struct expr_stmt : seq<ternary, sor<semi, after_block, missing_semi>> {};
// Inside a block, an expression right before '}' without ';' is the block's result.
struct block_result : at<one<'}'>> {};
struct block_expr_item : seq<ternary, sor<semi, after_block, block_result, missing_semi>> {};

// (The statements that begin with a keyword are tried only when a keyword is next.)
struct keyword_stmt : sor<let_stmt, var_stmt, def_stmt, import_stmt, if_stmt, for_stmt> {};
struct statement : sor<empty_stmt, seq<at<keyword>, keyword_stmt>, assign_stmt, expr_stmt>, nesting {};
struct block_statement : sor<empty_stmt, seq<at<keyword>, keyword_stmt>, assign_stmt, block_expr_item>, nesting {};

struct no_stray_brace : not_at<one<'}'>> {};  // "unmatched '}'"
struct end_of_file : eof {};                   // "expected a statement"
struct module : seq<opt<utf8::bom>, sp, star<statement>, no_stray_brace, end_of_file> {};

using grammar = module;

}  // namespace sdfc::grammar

namespace tao::pegtl {
// The custom rule matches nothing (a check on the position), for analyze<>().
template <typename Name>
struct analyze_traits<Name, sdfc::grammar::after_block> : analyze_opt_traits<> {};
// The hand-written rules are analyzed as the rules they stand for.
template <typename Name, typename Guard, typename Rule>
struct analyze_traits<Name, sdfc::grammar::when<Guard, Rule>> : analyze_traits<Name, typename seq<at<Guard>, Rule>::rule_t> {};
template <typename Name, typename... Keys>
struct analyze_traits<Name, sdfc::grammar::any_key<Keys...>> : analyze_traits<Name, typename sor<Keys...>::rule_t> {};
template <typename Name>
struct analyze_traits<Name, sdfc::grammar::sp>
    : analyze_traits<Name, typename star<sor<ascii::space, sdfc::grammar::line_comment, sdfc::grammar::block_comment>>::rule_t> {};
}  // namespace tao::pegtl
