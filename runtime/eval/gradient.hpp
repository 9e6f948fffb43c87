// Forward-mode gradients over the same bytecode as the batch VM: every register holds a
// value and its derivatives by x, y and z (a dual number). Each op's derivative comes from
// opcodes.def's own semantics column, expanded once more over dual numbers (gradient.cpp):
// the column's calls (om::exp_, om::min_, std::floor, ...) resolve to dual twins there, so an opcode
// whose semantics call a function without a twin does not compile. Exact normals for the
// mesher, one evaluation per point instead of six.
#pragma once
#include <cstdint>
#include <memory>

#include "compiler/bytecode/program.hpp"

namespace sdfc {

struct Dual {
    float v = 0.0f, dx = 0.0f, dy = 0.0f, dz = 0.0f;
};

class GradientEvaluator {
public:
    static constexpr int kLanes = 64;
    explicit GradientEvaluator(uint32_t max_regs);
    ~GradientEvaluator();
    GradientEvaluator(const GradientEvaluator&) = delete;
    GradientEvaluator& operator=(const GradientEvaluator&) = delete;

    // The tape's first output and its gradient at n <= kLanes points. Where the field has a
    // kink (min, max, abs, floor) the derivative is that of the side the VM takes.
    void eval(const TapeView& t, const float* x, const float* y, const float* z, int n, float time, Dual* out);

private:
    struct Regs;  // dual registers, kLanes per register
    std::unique_ptr<Regs> regs_;
};

}  // namespace sdfc
