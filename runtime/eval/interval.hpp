// Interval arithmetic over the same bytecode as the batch VM, and per-region tape
// simplification (Fidget / MPR): evaluating a Tape over a box gives an interval that
// encloses every value the VM computes for a point of the box (bit for bit, rounding
// included), and records for each min/max/select whether one side wins over the whole box.
// simplify() then drops the losing sides and everything only they used, and re-allocates
// registers, giving a shorter tape that computes exactly the same values inside the box.
//
// Unknown: an interval with both ends NaN means "some point may be NaN" (or an operand was
// infinite); it never decides a choice and propagates through every op (see interval.cpp).
#pragma once
#include <cstdint>
#include <array>
#include <memory>
#include <vector>

#include "compiler/bytecode/program.hpp"

namespace sdfc {

struct Interval {
    float lo, hi;
};

// Which side an op takes over a whole box (Min, Max, MinI, MaxI, Select).
enum : uint8_t {
    kChoiceBoth = 0,  // undecided: keep the op
    kChoiceA = 1,     // operand a
    kChoiceB = 2,     // operand b (MinI/MaxI: the immediate k)
    kChoiceC = 3,     // operand c (Select)
};
bool is_choice_op(Op op);

// The interval semantics of one op (scalar reference; the batch evaluator runs the same
// code per lane). Inputs (VarX...) and Const return a / [k, k]. `choice` receives the side.
Interval eval_interval(Op op, Interval a, Interval b, Interval c, float k, uint8_t* choice = nullptr);

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
};

inline constexpr int kIvLanes = 64;

// Evaluates a tape over up to kIvLanes boxes at once (structure of arrays, like the VM).
// Sized for the largest tape it will see (registers and choice slots); no allocation after.
class IntervalEvaluator {
public:
    IntervalEvaluator(uint32_t max_regs, uint32_t max_choices);

    // Lane i's box is [xlo[i], xhi[i]] x [ylo[i], yhi[i]] x [zlo[i], zhi[i]]; n <= kIvLanes.
    void eval(const Tape& t, const float* xlo, const float* xhi, const float* ylo, const float* yhi, const float* zlo,
              const float* zhi, int n, float time = 0.0f);

    Interval result(int lane) const { return {lo_[out_ * kIvLanes + lane], hi_[out_ * kIvLanes + lane]}; }
    // Choice of slot s for lane i: choices()[s * stride() + i] (stride: n rounded up to 8;
    // the buffer has 64 readable bytes past the last slot's row).
    const uint8_t* choices() const { return choices_.get(); }
    int stride() const { return stride_; }

private:
    uint32_t max_regs_, max_choices_;
    std::unique_ptr<float[], void (*)(float*)> lo_store_, hi_store_;
    float *lo_, *hi_;
    std::unique_ptr<uint8_t[]> choices_;
    int stride_ = 0;
    uint16_t out_ = 0;
};

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
//            (leaves), not for parents of further simplification (copies would pile up).
// The cost is about the parent's length plus the results' lengths.
void simplify_batch(const Tape& parent, const uint8_t* choices, int stride, uint64_t lanes, BatchScratch& s,
                    bool compact = true);

}  // namespace sdfc
