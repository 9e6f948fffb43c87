// Building blocks of the GLSL backend (compiler/glsl/glsl.cpp), exposed for tests: float
// literals, one opcode's expression from its opcodes.def template, and a whole register
// Program as a GLSL function.
#pragma once
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "compiler/bytecode/program.hpp"

namespace sdfc::glsl {

// A GLSL float literal that reads back as exactly `v`: `2.0`, `0.5`, `1e-04`, `(-3.0)`
// (negative values parenthesised so `-{a}` never becomes `--`), and bit-cast expressions
// for inf and NaN (GLSL has no literal for them).
std::string literal(float v);

// The GLSL expression of one instruction: the op's template from opcodes.def with {a} {b}
// {c} replaced by the operand expressions and {k} by literal(k).
std::string op_expr(Op op, std::string_view a, std::string_view b, std::string_view c, float k);

// How one program becomes one GLSL function.
struct FunctionSpec {
    std::string signature;   // e.g. "float map(vec3 p)"
    std::string var_prefix;  // SSA names: prefix + number ("d12")
    // Builds the function's final statement(s) from the outputs' expressions, e.g.
    // {"return " + outs[0] + ";"}. Each string is one line (without indentation).
    std::function<std::vector<std::string>(const std::vector<std::string>& outs)> finish;
    std::string indent = "    ";
    size_t inline_limit = 72;  // single-use expressions up to this length are inlined
    Loc quiet;                 // instructions at this location get no comment (the scene's implicit union)
};

// The program as a GLSL function. Instructions are walked in order and renamed to SSA
// variables (`float d3 = ...;`); inputs (p.x, sdf_time) and constants are written in place,
// and a value used once is folded into its user when short. A comment names the script
// line (file:line and the line's text) whenever it changes.
std::string function(const Program& prog, const FunctionSpec& spec);

// True when `prog` contains `op` (e.g. Noise3: the noise helper must be emitted).
bool uses_op(const Program& prog, Op op);

// The GLSL helpers that opcodes.def's templates call in these programs (sdf_noise;
// sdf_powf and sdf_atan2), each with a comment line, in the order they must come.
std::string op_helpers(std::initializer_list<const Program*> progs);

// Text safe inside a `//` comment of any GLSL dialect and of an HTML <script>: ASCII only,
// no line continuation, no "</".
std::string comment_text(std::string_view s);

}  // namespace sdfc::glsl
