// Stage 3: the register program ("tape"). Fixed-width instructions over a flat register
// file; immutable once built and shared by every thread (each thread owns its registers).
//
//  Instr (16 bytes):  | op:8 | pad:8 | out:16 | a:16 | b:16 | c:16 | pad:16 | k:f32 |
//  out := semantics(op)(R[a], R[b], R[c], k)   (see compiler/ir/opcodes.def)
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "compiler/ir/ir.hpp"

namespace sdfc {

struct Instr {
    Op op;
    uint8_t pad = 0;
    uint16_t out = 0, a = 0, b = 0, c = 0;
    float k = 0.0f;
};
static_assert(sizeof(Instr) == 16);

struct Program {
    std::vector<Instr> code;
    std::vector<Loc> locs;          // per instruction: the script location that made it
    uint32_t num_regs = 0;
    std::vector<uint16_t> outputs;  // register of each output
    std::vector<std::string> output_names;
    bool uses_time = false;
};

// Linear-scan register allocation over the live nodes reachable from `roots`; constant
// operands become immediates where an *_I form exists; Add(MulI(x), y) fuses to MulAddI.
Program codegen(const Graph& g, const std::vector<NodeId>& roots, const std::vector<std::string>& names);

// One line per instruction (`sdfc compile --emit bytecode`): index, mnemonic, registers,
// immediate, and the script line.
std::string disassemble(const Program& p);

// Reference evaluation of one point, one instruction at a time (tests, the constant folder's twin).
std::vector<float> eval_scalar(const Program& p, float x, float y, float z, float time = 0.0f);

}  // namespace sdfc
