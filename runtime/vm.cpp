#include "runtime/vm.hpp"

#include <cstdlib>
#include <algorithm>
#include <cstring>
#include <new>

namespace sdfc {
namespace {
void free_aligned(float* p) { std::free(p); }
float* alloc_regs(size_t count) {
    size_t bytes = (count * sizeof(float) + 63) / 64 * 64;
    void* p = std::aligned_alloc(64, bytes);
    if (!p) throw std::bad_alloc();
    std::memset(p, 0, bytes);
    return static_cast<float*>(p);
}
}  // namespace

Evaluator::Evaluator(const Program& program)
    : program_(&program),
      storage_(alloc_regs(static_cast<size_t>(program.num_regs) * kBatch), &free_aligned),
      regs_(storage_.get()) {}

void Evaluator::eval(const float* x, const float* y, const float* z, int n, float time) {
    const size_t bytes = sizeof(float) * static_cast<size_t>(n);
    for (const Instr& in : program_->code) {
        float* R = reg(in.out);
        const float* A = reg(in.a);
        const float* B = reg(in.b);
        const float* C = reg(in.c);
        const float k = in.k;
        switch (in.op) {
            // Every row of the opcode table: inputs are copied in, the rest is one lane
            // loop over the row's semantics, which the compiler vectorises.
#define OP(name, mn, ar, imm, sem, glsl)                                           \
    case Op::name:                                                                 \
        if constexpr (Op::name == Op::VarX) std::memcpy(R, x, bytes);              \
        else if constexpr (Op::name == Op::VarY) std::memcpy(R, y, bytes);         \
        else if constexpr (Op::name == Op::VarZ) std::memcpy(R, z, bytes);         \
        else if constexpr (Op::name == Op::Time) std::fill_n(R, n, time);          \
        else                                                                       \
            for (int i = 0; i < n; ++i) {                                          \
                [[maybe_unused]] const float a = A[i];                             \
                [[maybe_unused]] const float b = B[i];                             \
                [[maybe_unused]] const float c = C[i];                             \
                R[i] = (sem);                                                      \
            }                                                                      \
        break;
#include "compiler/opcodes.def"
#undef OP
        }
    }
}

float Evaluator::eval1(float x, float y, float z, float time) {
    eval(&x, &y, &z, 1, time);
    return output(0)[0];
}

}  // namespace sdfc
