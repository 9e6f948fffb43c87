// The opcode enum and per-opcode facts, expanded from compiler/ir/opcodes.def.
#pragma once
#include <cstdint>
#include <string_view>

#include "compiler/ir/op_math.hpp"

namespace sdfc {

enum class Op : uint8_t {
#define OP(name, mn, ar, imm, sem, glsl) name,
#include "compiler/ir/opcodes.def"
#undef OP
};

inline constexpr int kOpCount = 0
#define OP(name, mn, ar, imm, sem, glsl) +1
#include "compiler/ir/opcodes.def"
#undef OP
    ;

struct OpInfo {
    std::string_view mnemonic;
    int arity;
    bool has_imm;
    std::string_view glsl;
};

inline constexpr OpInfo kOpInfo[] = {
#define OP(name, mn, ar, imm, sem, glsl) {mn, ar, imm != 0, glsl},
#include "compiler/ir/opcodes.def"
#undef OP
};

inline const OpInfo& op_info(Op op) { return kOpInfo[static_cast<int>(op)]; }

// Inputs are set by the evaluator, not computed from operands.
inline bool is_input(Op op) { return op == Op::VarX || op == Op::VarY || op == Op::VarZ || op == Op::Time; }

// Scalar semantics of one op (constant folding, reference evaluation).
inline float eval_op(Op op, float a, float b, float c, float k) {
    switch (op) {
#define OP(name, mn, ar, imm, sem, glsl) \
    case Op::name: return (sem);
#include "compiler/ir/opcodes.def"
#undef OP
    }
    return 0.0f;
}

}  // namespace sdfc
