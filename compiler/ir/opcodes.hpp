// The opcode enum and per-opcode facts, expanded from compiler/ir/opcodes.def.
#pragma once
#include <cstdint>
#include <string_view>

#include "compiler/ir/op_math.hpp"

namespace sdfc {

enum class Op : uint8_t {
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl) name,
#include "compiler/ir/opcodes.def"
#undef OP
};

inline constexpr int kOpCount = 0
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl) +1
#include "compiler/ir/opcodes.def"
#undef OP
    ;

// When an interval result is NaN, i.e. unknown (interval arithmetic in runtime/eval/interval.cpp):
//   Inputs  NaN when an operand has a NaN or infinite end (x * 0 is NaN for inf and NaN;
//           a finite sum that overflows only makes the result unknown needlessly)
//   Result  NaN when the result has a NaN or infinite end: enough for ops whose formulas
//           carry a NaN or infinite operand end into the result (add, sub)
//   B       NaN when operand b is unknown: min/max carry a's NaN ends (mn(NaN, x) is NaN)
//           but not b's, and infinities are fine for them
//   None    ops that carry NaN ends, with explicit checks for the NaN their operands can
//           make: the root of a negative number, inf - inf, 0 * inf, inf / inf, ... An
//           infinite end is a value like any other (exp overflows to inf, log(0) is -inf),
//           so smooth unions of exponentials keep their intervals
enum class OpPoison { Inputs, Result, B, None };

struct OpInfo {
    std::string_view mnemonic;
    int arity;
    bool has_imm;
    bool choice;  // min/max/select: intervals record which operand decided
    OpPoison poison;
    std::string_view glsl;
};

inline constexpr OpInfo kOpInfo[] = {
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl) {mn, ar, imm != 0, choice_ != 0, OpPoison::poison_, glsl},
#include "compiler/ir/opcodes.def"
#undef OP
};

inline const OpInfo& op_info(Op op) { return kOpInfo[static_cast<int>(op)]; }

// Inputs are set by the evaluator, not computed from operands.
inline bool is_input(Op op) { return op == Op::VarX || op == Op::VarY || op == Op::VarZ || op == Op::Time || op == Op::Param; }

// Scalar semantics of one op (constant folding, reference evaluation).
inline float eval_op(Op op, float a, float b, float c, float k) {
    switch (op) {
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl) \
    case Op::name: return (sem);
#include "compiler/ir/opcodes.def"
#undef OP
    }
    return 0.0f;
}

}  // namespace sdfc
