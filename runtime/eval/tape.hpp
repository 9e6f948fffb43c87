// The tape of the interval evaluator and of tape simplification: one output of a Program,
// or a shortened copy of one, plus the def links simplify() follows (runtime/eval/simplify.hpp).
// Choice ops (min, max, select) are the ops whose winning side an interval can decide.
#pragma once
#include <cstdint>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "compiler/bytecode/program.hpp"

namespace sdfc {

// Which side an op takes over a whole box (Min, Max, MinI, MaxI, Select).
enum : uint8_t {
    kChoiceBoth = 0,  // undecided: keep the op
    kChoiceA = 1,     // operand a
    kChoiceB = 2,     // operand b (MinI/MaxI: the immediate k)
    kChoiceC = 3,     // operand c (Select)
};
// The lanes (of the first 64) whose choice byte in a slot's row equals v: the interval
// evaluator's row is readable 64 bytes on (IntervalEvaluator::choices).
inline uint64_t choice_lanes(const uint8_t* row, uint8_t v) {
#if defined(__SSE2__)
    const __m128i want = _mm_set1_epi8(char(v));
    uint64_t m = 0;
    for (int q = 0; q < 4; ++q) {
        __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + 16 * q));
        m |= uint64_t(uint32_t(_mm_movemask_epi8(_mm_cmpeq_epi8(x, want)) & 0xFFFF)) << (16 * q);
    }
    return m;
#else
    uint64_t m = 0;
    for (int i = 0; i < 64; ++i) m |= uint64_t(row[i] == v) << i;
    return m;
#endif
}
// A bit test, not a chain of compares: link() asks it for every instruction, and the
// branches of a chain mispredict on mixed code (measured: link() took twice as long). The
// bits are opcodes.def's choice column.
inline constexpr uint64_t kChoiceOps = 0
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl) | (uint64_t(choice_ != 0) << int(Op::name))
#include "compiler/ir/opcodes.def"
#undef OP
    ;
static_assert(kOpCount <= 64);
constexpr bool is_choice_op(Op op) { return (kChoiceOps >> int(op)) & 1; }

// Instr::pad bit: only whether this min/max's result is < 0 matters to the tape's output,
// which is itself only tested for < 0 (a 2D image's inside). The interval evaluator may
// then also decide the op by sign alone: min(a, b) with a >= 0 over the whole box is b as
// far as "< 0" goes, even where a and b overlap. Simplified tapes keep the bit (it stays
// true: a winner inherits only the sign-only uses of the op it replaces).
inline constexpr uint8_t kSignOnly = 1;
// Instr::pad bit: a Min in a chain of mins up to the output (every use is such a Min, the
// output, or a guard's threshold, which only decides skipping). Over a box, an operand
// whose lower bound exceeds an upper bound of the rest of the chain can never be the
// result: IntervalEvaluator::prune_min_chains drops it even where its sibling's interval
// overlaps it (a union's far shapes, against the nearest shape anywhere in the union).
inline constexpr uint8_t kMinChain = 2;
inline bool is_chain_min(const Instr& in) { return in.op == Op::Min && (in.pad & kMinChain); }

// A straight-line program with one output: a Program's output, or a shortened copy.
// link() adds what simplify() needs to visit only the live part of a tape: for every
// operand the index of the instruction that defined its value (registers are reused, so
// this is the last earlier write of the register), and each choice op's slot.
struct Tape {
    static constexpr uint32_t kNone = 0xFFFFFFFFu;
    std::vector<Instr> code;
    uint16_t out = 0;        // output register
    uint32_t num_regs = 1;   // registers used (a VM register file this big suffices)
    uint32_t choices = 0;    // instructions with is_choice_op, in order: their "slots"
    // link(): per instruction, the instructions defining its operands a, b, c (kNone: unused)
    // and its choice slot (kNone: not a choice op).
    struct Link {
        uint32_t def[3];
        uint32_t slot;
    };
    std::vector<Link> links;
    uint32_t out_def = kNone;    // the instruction defining the output
    bool linked = false;
    bool well_formed = false;    // known: every operand is written before it is read (simplify's output)

    static Tape from(const Program& p, int output = 0);
    void assign(const Instr* code, size_t count, uint16_t out_reg, uint32_t regs);  // a child of simplify_batch
    void recount();  // sets num_regs and choices from code
    void link();     // fills links and out_def
    // Sets kSignOnly on the min/max ops whose every use is a sign-only min/max or the
    // output (linked tapes only): for tapes whose output is only tested for < 0.
    void mark_sign_only();
    // Sets kMinChain (linked tapes only); see above.
    void mark_min_chains();

    // (choices is only sure once linked: assign() leaves it stale)
    TapeView view() const {
        return {code.data(), uint32_t(code.size()), &out, 1, num_regs, linked ? choices : TapeView::kUncounted};
    }
};

}  // namespace sdfc
