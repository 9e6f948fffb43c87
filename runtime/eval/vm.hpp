// The batch VM: evaluates a Program on up to kBatch points at once, structure of arrays,
// one switch per instruction and a tight loop over the lanes (which the compiler
// vectorises). No allocation after construction; one Evaluator per thread.
#pragma once
#include <cstddef>
#include <memory>
#include <vector>

#include "compiler/bytecode/program.hpp"

namespace sdfc {

inline constexpr int kBatch = 64;

class Evaluator {
public:
    explicit Evaluator(const Program& program);
    Evaluator(const Evaluator&) = delete;
    Evaluator& operator=(const Evaluator&) = delete;

    // Evaluates n <= kBatch points; results readable through output(i) until the next call.
    void eval(const float* x, const float* y, const float* z, int n, float time = 0.0f);
    const float* output(int i) const { return reg(program_->outputs[static_cast<size_t>(i)]); }

    // Runs `count` instructions of another tape (e.g. a simplified one, runtime/eval/interval.hpp)
    // on this register file; it must use at most program().num_regs registers. Read the
    // result with reg_data(its output register).
    void eval_code(const Instr* code, size_t count, const float* x, const float* y, const float* z, int n,
                   float time = 0.0f);
    const float* reg_data(uint32_t r) const { return reg(r); }

    // Convenience: one point, first output.
    float eval1(float x, float y, float z, float time = 0.0f);

    const Program& program() const { return *program_; }

private:
    float* reg(uint32_t r) { return regs_ + static_cast<size_t>(r) * kBatch; }
    const float* reg(uint32_t r) const { return regs_ + static_cast<size_t>(r) * kBatch; }
    const Program* program_;
    std::unique_ptr<float[], void (*)(float*)> storage_;
    float* regs_;
};

}  // namespace sdfc
