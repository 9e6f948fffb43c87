// The syntax error messages, keyed by the grammar rule that failed (PEGTL's must_if style:
// a rule with a message raises it as soon as it fails). Only error-point rules appear here;
// see the conventions at the top of sdf_grammar.hpp. lang/parser.cpp turns the raised
// tao::pegtl::parse_error into a CompileError at the failure point.
#pragma once
#include "grammar/sdf_grammar.hpp"

namespace sdfc::grammar {

template <typename Rule>
inline constexpr const char* error_message = nullptr;

// Lexical (reported at the opening "/*", quote or backslash).
template <> inline constexpr const char* error_message<block_comment_body> = "unterminated comment";
template <> inline constexpr const char* error_message<string_body> = "unterminated string";
template <> inline constexpr const char* error_message<escape_seq> =
    "unknown escape sequence in a string (use \\\", \\\\, \\n or \\t)";
template <> inline constexpr const char* error_message<exponent_digits> = "expected digits in the number's exponent";

// Punctuation.
template <> inline constexpr const char* error_message<expect_rparen> = "expected ')'";
template <> inline constexpr const char* error_message<expect_rbracket> = "expected ']'";
template <> inline constexpr const char* error_message<expect_equals> = "expected '=' after the name";
template <> inline constexpr const char* error_message<expect_semi> = "expected ';' after the statement";
template <> inline constexpr const char* error_message<missing_semi> = "expected ';' after the statement";
template <> inline constexpr const char* error_message<block_close> = "expected '}'";
template <> inline constexpr const char* error_message<vector_close> = "expected ',' or ']'";
template <> inline constexpr const char* error_message<range_close> = "expected ']' to close the range";

// Expressions.
template <> inline constexpr const char* error_message<expect_expr> = "expected an expression";
template <> inline constexpr const char* error_message<index_expr> = "expected an expression";
template <> inline constexpr const char* error_message<branch_expr> = "expected an expression";
template <> inline constexpr const char* error_message<value_expr> = "expected an expression after '='";
template <> inline constexpr const char* error_message<neg_operand> = "expected an expression after '-'";
template <> inline constexpr const char* error_message<not_operand> = "expected an expression after '!'";
template <> inline constexpr const char* error_message<mul_rhs> = "expected an expression after the operator";
template <> inline constexpr const char* error_message<add_rhs> = "expected an expression after the operator";
template <> inline constexpr const char* error_message<cmp_rhs> = "expected an expression after the operator";
template <> inline constexpr const char* error_message<and_rhs> = "expected an expression after '&&'";
template <> inline constexpr const char* error_message<or_rhs> = "expected an expression after '||'";
template <> inline constexpr const char* error_message<ternary_then> = "expected an expression after '?'";
template <> inline constexpr const char* error_message<ternary_colon> =
    "expected ':' in the conditional expression (cond ? a : b)";
template <> inline constexpr const char* error_message<ternary_else> = "expected an expression after ':'";
template <> inline constexpr const char* error_message<swizzle_letters> = "expected swizzle letters (such as .xyz) after '.'";

// for / if headers.
template <> inline constexpr const char* error_message<for_lparen> = "expected '(' after 'for'";
template <> inline constexpr const char* error_message<binding_name> = "expected a loop variable name";
template <> inline constexpr const char* error_message<for_iterable> = "expected a range or a vector to iterate over";
template <> inline constexpr const char* error_message<for_rparen> = "expected ')' after the loop variables";
template <> inline constexpr const char* error_message<if_lparen> = "expected '(' after 'if'";
template <> inline constexpr const char* error_message<condition> = "expected a condition";
template <> inline constexpr const char* error_message<if_rparen> = "expected ')' after the condition";

// field (p) -> body
template <> inline constexpr const char* error_message<field_param> =
    "expected '(' and the field's parameter name, as in field (p) -> ...";
template <> inline constexpr const char* error_message<expect_arrow> = "expected '->' after the field's parameter";
template <> inline constexpr const char* error_message<field_body> = "expected an expression after '->'";

// Statements.
template <> inline constexpr const char* error_message<let_name> = "expected a name after 'let'";
template <> inline constexpr const char* error_message<var_name> = "expected a name after 'var'";
template <> inline constexpr const char* error_message<def_name> = "expected a name after 'def'";
template <> inline constexpr const char* error_message<def_lparen> = "expected '(' after the function name";
template <> inline constexpr const char* error_message<expect_param_name> = "expected a parameter name";
template <> inline constexpr const char* error_message<params_close> = "expected ')' after the parameters";
template <> inline constexpr const char* error_message<missing_def_body> = "expected '=' or '{' after the parameters";
template <> inline constexpr const char* error_message<import_path> = "expected a path string after 'import'";
template <> inline constexpr const char* error_message<body_stmt> = "expected a statement";
template <> inline constexpr const char* error_message<no_stray_brace> = "unmatched '}'";
template <> inline constexpr const char* error_message<end_of_file> = "expected a statement";

// The `Errors` argument of tao::pegtl::must_if.
struct errors {
    template <typename Rule>
    static constexpr const char* message = error_message<Rule>;
};

}  // namespace sdfc::grammar
