// Tape simplification (Fidget / MPR): given the choices an IntervalEvaluator recorded for a
// box (runtime/eval/interval.hpp), drop the losing side of every decided min/max/select and
// everything only it used, and re-allocate registers: a shorter tape that computes exactly
// the same floats as its parent inside the box.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

#include "runtime/eval/tape.hpp"

namespace sdfc {

// Scratch for simplify(), reused across calls (one per thread).
struct SimplifyScratch {
    std::vector<uint64_t> live;     // bit per parent instruction: value needed, not yet visited
    std::vector<uint16_t> bind;     // per parent instruction: register of its value (when live)
    std::vector<uint16_t> free_regs;
    std::vector<Instr> rev;         // emitted instructions, last first
};

// The tape `parent` (linked) shortened for one box: the choices of `lane` (from an
// IntervalEvaluator::eval of `parent`) replace decided ops by the winning operand, dead
// code goes, and registers are re-allocated (backwards linear scan; an op's output may
// share an operand's register, which the lane-wise VM allows). Only live instructions are
// visited (def links), so the cost is about the size of the result. `out` computes exactly
// what `parent` computes at every point of that box, and is linked (ready to be simplified
// further). A parent that is not linked (or reads unwritten registers) is copied as is.
void simplify(const Tape& parent, const uint8_t* choices, int stride, int lane, Tape& out, SimplifyScratch& s);

// Scratch and result of simplify_batch: lane j's tape is code(j)[0 .. len[j]), output
// register out[j], regs[j] registers.
struct BatchScratch {
    std::vector<uint64_t> mask;  // per parent instruction: lanes needing its value
    std::unique_ptr<Instr[], void (*)(Instr*)> buf{nullptr, [](Instr* p) { ::operator delete(p); }};
    std::unique_ptr<uint32_t[]> idx;  // per lane: live parent instructions
    size_t buf_size = 0, idx_size = 0, cap = 0;
    std::vector<uint16_t> bind, free_regs;
    std::array<uint32_t, 64> start{}, len{}, regs{};
    std::array<uint16_t, 64> out{};
    const Instr* code(int lane) const { return buf.get() + size_t(lane) * cap + start[size_t(lane)]; }
    TapeView view(int lane) const {
        const size_t j = size_t(lane);
        return {code(lane), len[j], &out[j], 1, regs[j]};
    }
};

// simplify() for many boxes at once: for each lane in `lanes` (bits of the last
// IntervalEvaluator::eval of `parent`), a tape computing what `parent` computes in that
// lane's box. One backward pass over the parent finds every lane's live instructions (64
// lanes at once, as bit masks, following only the winners of decided choices). Then
//   compact: each lane's short list alone is register-allocated, decided choices vanish
//            (the winner takes over the register; a copy only if the winner is also
//            used elsewhere): as short as simplify()'s tapes;
//   else:    a trace: the live instructions in the parent's registers, a decided choice
//            op replaced by a copy of its winner (nothing if already in place) or by a
//            constant. Cheaper to make, a little longer: for tapes evaluated once
//            (leaves) or simplified once more (raster2d's tiles above its leaves), not
//            for longer lines of descendants (copies would pile up).
// The cost is about the parent's length plus the results' lengths.
void simplify_batch(const Tape& parent, const uint8_t* choices, int stride, uint64_t lanes, BatchScratch& s,
                    bool compact = true);

// Rewrites max(x, -x) (either order, through copies and double negations) as abs(x):
// the same floats but for the sign of a zero result, and an interval that knows it is not
// negative. A box where a simplification left this (coincident faces of a CSG model, whose
// difference keeps a sheet of zero thickness) is then proven free of negative values.
// Returns whether it rewrote anything (registers may be written more than once, as in any
// tape: operands are followed by value, not by register).
bool fold_abs(Instr* code, size_t count, std::vector<uint32_t>& scratch);

// Only simplify_batch's backward pass: s.mask[i] holds the lanes needing instruction i of
// `parent` (nothing when `parent` cannot be followed: not linked, or no output). SweepVM
// (runtime/eval/vm.hpp) runs the lanes from these masks without making their tapes.
void simplify_masks(const Tape& parent, const uint8_t* choices, int stride, uint64_t lanes, BatchScratch& s);

}  // namespace sdfc
