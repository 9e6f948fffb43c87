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
    uint8_t pad = 0;  // evaluator hints (runtime/eval/tape.hpp: kSignOnly, kMinChain); the VM ignores them
    uint16_t out = 0, a = 0, b = 0, c = 0;
    float k = 0.0f;
};
static_assert(sizeof(Instr) == 16);

// What an evaluator needs of a tape at eval time: evaluators own only scratch (a register
// file of num_regs), so one evaluator runs any tape that fits, Fidget's model. A Program,
// an interval Tape and a simplified leaf tape (runtime/eval/tape.hpp, simplify.hpp) each give
// one with view(); the view borrows their storage.
struct Guard;
struct TapeView {
    static constexpr uint32_t kUncounted = 0xFFFFFFFFu;
    const Instr* code = nullptr;
    uint32_t len = 0;
    const uint16_t* outputs = nullptr;  // register of each output
    uint32_t num_outputs = 0;
    uint32_t num_regs = 0;              // registers the code uses (0: unknown, the caller sized the evaluator)
    uint32_t choices = kUncounted;      // min/max/select ops in code: interval choice slots
    // The Program's guards (Guard below), for code that is a Program's own: the batch VM then
    // skips guarded regions that every point of a batch is far from. Null for shortened
    // tapes (their guards' ends no longer hold): those run through.
    const Guard* guards = nullptr;
    uint16_t output(uint32_t i = 0) const { return outputs[i]; }
};

// What a `guard` instruction (Op::Guard, its k the index here) knows of its region:
// instructions (guard, end) compute a union's child (compiler/scene/shapes_csg.cpp), whose
// surface lies in the box [lo, hi] around the point in registers (px, py, pz). Where the
// point is outside the box by at least the guard's threshold register (the union's distance
// so far), the child cannot be nearer: an evaluator may jump to `end`, leaving +inf in the
// guard's out, which the region's last instruction would have written. The child's other
// results (its material channels) then keep stale values that the union's choices never
// pick. Evaluators that do not skip run through: the result is the same.
struct Guard {
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    uint16_t px = 0, py = 0, pz = 0;
    uint32_t end = 0;
};

// A guard instruction's entry in Program::guards: its k (operand fields hold registers only).
inline size_t guard_index(const Instr& in) { return static_cast<size_t>(in.k); }

struct Program {
    std::vector<Instr> code;
    std::vector<Guard> guards;      // of the guard instructions (k: the index), in order
    std::vector<Loc> locs;          // per instruction: the script location that made it
    uint32_t num_regs = 0;
    std::vector<uint16_t> outputs;  // register of each output
    std::vector<std::string> output_names;
    bool uses_time = false;

    TapeView view() const {
        return {code.data(), uint32_t(code.size()), outputs.data(), uint32_t(outputs.size()), num_regs,
                TapeView::kUncounted, guards.empty() ? nullptr : guards.data()};
    }
};

// Whether the program reads the point (x, y or z): one that does not is the same everywhere.
inline bool reads_point(const Program& p) {
    for (const Instr& in : p.code)
        if (in.op == Op::VarX || in.op == Op::VarY || in.op == Op::VarZ) return true;
    return false;
}

// Linear-scan register allocation over the live nodes reachable from `roots`; constant
// operands become immediates where an *_I form exists; Add(MulI(x), y) fuses to MulAddI.
// The graph's guarded regions (Graph::guards) become guard instructions, each region's
// instructions scheduled together after its guard.
Program codegen(const Graph& g, const std::vector<NodeId>& roots, const std::vector<std::string>& names);

// One line per instruction (`sdfc compile --emit bytecode`): index, mnemonic, registers,
// immediate, and the script line.
std::string disassemble(const Program& p);

// Reference evaluation of one point, one instruction at a time (tests, the constant folder's
// twin). `skip`: jump over guarded regions whose guard allows it (guard_skips), as the GLSL
// tape interpreter does; the outputs are the same but where a shape's distance is a loose bound.
std::vector<float> eval_scalar(const Program& p, float x, float y, float z, float time = 0.0f, bool skip = false);
// Whether the guard `in` (Op::Guard) lets an evaluator skip its region, given the registers.
bool guard_skips(const Program& p, const Instr& in, const float* regs);

// The first output of `p` at n points, into out: how a stage below the runtime samples a
// field (the raw-field Lipschitz estimate). sample_scalar is the reference; the runtime's
// sample_batch (runtime/eval/vm.hpp) gives the same values through the batch VM, faster.
using FieldSampler = void (*)(const Program& p, const float* x, const float* y, const float* z, size_t n, float time,
                              float* out);
void sample_scalar(const Program& p, const float* x, const float* y, const float* z, size_t n, float time, float* out);

}  // namespace sdfc
