// Interval arithmetic over the same bytecode as the batch VM (Fidget / MPR): evaluating a
// tape over a box gives an interval that encloses every value the VM computes for a point
// of the box (bit for bit, rounding included), and records for each min/max/select whether
// one side wins over the whole box. simplify() (runtime/eval/simplify.hpp, included here)
// then drops the losing sides, giving a shorter tape exact inside the box.
//
// Unknown: an interval with both ends NaN means "some point may be NaN" (or an operand was
// infinite); it never decides a choice and propagates through every op (see interval.cpp).
#pragma once
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "compiler/bytecode/program.hpp"
#include "runtime/eval/simplify.hpp"
#include "runtime/eval/tape.hpp"

namespace sdfc {

struct Interval {
    float lo, hi;
};

// The interval semantics of one op (scalar reference; the batch evaluator runs the same
// code per lane). Inputs (VarX...) and Const return a / [k, k]. `choice` receives the side.
Interval eval_interval(Op op, Interval a, Interval b, Interval c, float k, uint8_t* choice = nullptr);

// The interval of a 1-Lipschitz bound over a box whose diagonal is `diagonal` long,
// tightened with the bound's value at the box's centre: it is within half the diagonal of
// it (the margin covers the floats). Rescues fields whose intervals are weak far away.
// An unknown interval (NaN: the arithmetic lost track, as in a fractal's escape loop)
// stays unknown: a field written as a distance estimate near its surface (a Mandelbulb's
// 0.5 log(r) r / dr) is far above the distance far from it, and a big cell's centre value
// would then "prove" the cell empty, surface and all.
inline Interval tighten_by_centre(Interval v, float centre, float diagonal) {
    if (std::isnan(v.lo) || std::isnan(v.hi)) return v;
    const float r = 0.5f * diagonal * (1.0f + 1e-5f) + 1e-6f * (1.0f + std::fabs(centre));
    if (!(v.lo >= centre - r)) v.lo = centre - r;
    if (!(v.hi <= centre + r)) v.hi = centre + r;
    return v;
}

inline constexpr int kIvLanes = 64;

// Evaluates a tape's first output over up to kIvLanes boxes at once (structure of arrays,
// like the VM). Owns only scratch: registers and choice slots, sized at construction for
// the largest tape it will see (a bigger one grows them: the only allocation after).
class IntervalEvaluator {
public:
    IntervalEvaluator(uint32_t max_regs, uint32_t max_choices);

    // Lane i's box is [xlo[i], xhi[i]] x [ylo[i], yhi[i]] x [zlo[i], zhi[i]]; n <= kIvLanes.
    void eval(const TapeView& t, const float* xlo, const float* xhi, const float* ylo, const float* yhi,
              const float* zlo, const float* zhi, int n, float time = 0.0f);
    void eval(const Tape& t, const float* xlo, const float* xhi, const float* ylo, const float* yhi, const float* zlo,
              const float* zhi, int n, float time = 0.0f) {
        eval(t.view(), xlo, xhi, ylo, yhi, zlo, zhi, n, time);
    }
    void reserve(uint32_t regs, uint32_t choices);
    // With keep_chains (for tapes marked by Tape::mark_min_chains), eval also keeps the
    // operand intervals of chain mins, and prune_min_chains(t, n) then decides more of their
    // choices, for the output of the whole chain: the tape simplified with them computes
    // the same floats at the output as t in each box (not at the chain's inner mins).
    void keep_chains(bool on) { keep_chains_ = on; }
    void prune_min_chains(const Tape& t, int n);

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
    bool keep_chains_ = false;
    std::vector<float> chain_;  // per choice slot: al, ah, bl, bh rows of stride_ lanes
    std::vector<float> bound_;  // prune_min_chains: per choice slot and lane
    uint8_t chain_unknown_[kIvLanes] = {};  // per lane: some chain operand's interval is unknown (NaN)
};

}  // namespace sdfc
