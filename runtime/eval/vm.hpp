// The batch VM: evaluates a tape on up to kBatch points at once, structure of arrays, one
// switch per instruction and a tight loop over the lanes (which the compiler vectorises).
// The VM owns only its register file; the tape is an argument of eval (a TapeView of a
// Program, an interval Tape or a simplified leaf), so one VM per thread runs every tape.
#pragma once
#include <cstddef>
#include <memory>
#include <vector>

#include "compiler/bytecode/program.hpp"
#include "runtime/eval/tape.hpp"

namespace sdfc {

inline constexpr int kBatch = 64;

class BatchVM {
public:
    explicit BatchVM(uint32_t max_regs);
    BatchVM(const BatchVM&) = delete;
    BatchVM& operator=(const BatchVM&) = delete;

    // Evaluates n <= kBatch points; results readable through output(t, i) or reg_data until
    // the next call. A tape needing more than max_regs() registers grows the register file
    // (the only allocation after construction); one with num_regs 0 must fit.
    void eval(const TapeView& t, const float* x, const float* y, const float* z, int n, float time = 0.0f);
    const float* output(const TapeView& t, uint32_t i = 0) const { return reg(t.output(i)); }
    const float* reg_data(uint32_t r) const { return reg(r); }
    uint32_t max_regs() const { return max_regs_; }
    void reserve(uint32_t regs);  // register file of at least `regs` registers

private:
    float* reg(uint32_t r) { return regs_ + static_cast<size_t>(r) * kBatch; }
    const float* reg(uint32_t r) const { return regs_ + static_cast<size_t>(r) * kBatch; }
    uint32_t max_regs_ = 0;
    std::unique_ptr<float[], void (*)(float*)> storage_;
    float* regs_ = nullptr;
};

// Many lanes of an interval pass evaluated at once, each lane a batch of kBatch points of
// its own box (raster2d's leaves: the 8 x 8 pixels of each child of a tile): one walk over
// the parent tape `t` (linked), each instruction run for the lanes whose need mask (`need`,
// from simplify_masks) holds it, with each lane's decided choices. Bit for bit what
// simplify_batch(compact = false) and a BatchVM::eval of each lane's trace give, without
// writing the traces; and one lane's op does not wait for another's result, as a trace's
// next op waits for the one before (the VM's registers are memory). The lanes' register
// files take at most max_floats floats (4 MB by default): a tape with thousands of
// registers runs its lanes in several passes.
class SweepVM {
public:
    explicit SweepVM(size_t max_floats = size_t(1) << 20) : max_floats_(max_floats) {}
    // Lane j (each bit of `lanes`) reads x[j], y[j] and z[j], kBatch points each (z null:
    // every z is 0).
    void eval(const Tape& t, const uint8_t* choices, int stride, const uint64_t* need, uint64_t lanes,
              const float* const* x, const float* const* y, const float* const* z, float time);
    const float* output(int lane) const { return out_[lane]; }

private:
    size_t max_floats_;
    std::unique_ptr<float[], void (*)(float*)> storage_{nullptr, nullptr};
    std::unique_ptr<float[]> outs_;  // the lanes' outputs, when not all lanes fit one pass
    size_t size_ = 0;                // floats
    float* base_[64] = {};
    const float* out_[64] = {};
};

// sample_scalar's values through the batch VM (a FieldSampler, see program.hpp).
void sample_batch(const Program& p, const float* x, const float* y, const float* z, size_t n, float time, float* out);

// A BatchVM bound to one Program: the older interface (eval without a tape, output(i)).
class Evaluator : public BatchVM {
public:
    explicit Evaluator(const Program& program) : BatchVM(program.num_regs), program_(&program) {}

    using BatchVM::eval;
    using BatchVM::output;
    void eval(const float* x, const float* y, const float* z, int n, float time = 0.0f) {
        BatchVM::eval(program_->view(), x, y, z, n, time);
    }
    const float* output(int i) const { return reg_data(program_->outputs[static_cast<size_t>(i)]); }

    // Convenience: one point, first output.
    float eval1(float x, float y, float z, float time = 0.0f) {
        eval(&x, &y, &z, 1, time);
        return output(0)[0];
    }

    const Program& program() const { return *program_; }

private:
    const Program* program_;
};

}  // namespace sdfc
