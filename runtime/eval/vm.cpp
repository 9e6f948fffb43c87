#include "runtime/eval/vm.hpp"

#include <algorithm>
#include <cstdlib>
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

// Lanes are processed in groups of kGroup (one AVX2 vector of floats); a batch of n points
// runs ceil(n / kGroup) groups, the extra lanes compute on stale but harmless values.
constexpr int kGroup = 8;
static_assert(kBatch % kGroup == 0);

// The output register may be one of the operand registers (codegen reuses a dying
// operand's register), but only lane i is ever read to write lane i, so the loops carry no
// dependence; tell the vectoriser so it neither versions nor falls back to scalar code.
#if defined(__clang__)
#define SDFC_IVDEP _Pragma("clang loop vectorize(assume_safety)")
#elif defined(__GNUC__)
#define SDFC_IVDEP _Pragma("GCC ivdep")
#else
#define SDFC_IVDEP
#endif
}  // namespace

Evaluator::Evaluator(const Program& program)
    : program_(&program),
      storage_(alloc_regs(static_cast<size_t>(program.num_regs) * kBatch), &free_aligned),
      regs_(storage_.get()) {}

// One pass over the program with the lane count M known at compile time when FULL (the
// loops unroll completely) or given at run time (m, a multiple of kGroup) otherwise.
// Dispatch is a computed goto with one indirect jump per handler (GCC/clang), which the
// branch predictor learns per opcode, or a switch elsewhere.
template <bool FULL>
static inline void run(const Instr* code, const Instr* end, float* base, const float* x, const float* y,
                       const float* z, int n, int m_rt, float time) {
    const int m = FULL ? kBatch : m_rt;
    auto load = [&](float* R, const float* src) {
        std::memcpy(R, src, sizeof(float) * static_cast<size_t>(n));
        for (int i = n; i < m; ++i) R[i] = src[n - 1];  // keep padding lanes finite
    };
    const Instr* ip = code;
    if (ip == end) return;
#if defined(__GNUC__)
    static const void* const labels[] = {
#define OP(name, mn, ar, imm, sem, glsl) &&L_##name,
#include "compiler/ir/opcodes.def"
#undef OP
    };
#define SDFC_NEXT                     \
    do {                              \
        if (++ip == end) return;      \
        goto* labels[int(ip->op)];    \
    } while (0)
    goto* labels[int(ip->op)];
#define SDFC_CASE(name) L_##name:
#else
#define SDFC_NEXT break
#define SDFC_CASE(name) case Op::name:
    for (; ip != end; ++ip)
        switch (ip->op) {
#endif
#define OP(name, mn, ar, imm, sem, glsl)                                           \
    SDFC_CASE(name) {                                                              \
        float* R = base + static_cast<size_t>(ip->out) * kBatch;                   \
        [[maybe_unused]] const float* A = base + static_cast<size_t>(ip->a) * kBatch; \
        [[maybe_unused]] const float* B = base + static_cast<size_t>(ip->b) * kBatch; \
        [[maybe_unused]] const float* C = base + static_cast<size_t>(ip->c) * kBatch; \
        [[maybe_unused]] const float k = ip->k;                                    \
        if constexpr (Op::name == Op::VarX) load(R, x);                            \
        else if constexpr (Op::name == Op::VarY) load(R, y);                       \
        else if constexpr (Op::name == Op::VarZ) load(R, z);                       \
        else if constexpr (Op::name == Op::Time) std::fill_n(R, m, time);          \
        else {                                                                     \
            SDFC_IVDEP                                                             \
            for (int i = 0; i < m; ++i) {                                          \
                [[maybe_unused]] const float a = A[i];                             \
                [[maybe_unused]] const float b = B[i];                             \
                [[maybe_unused]] const float c = C[i];                             \
                R[i] = (sem);                                                      \
            }                                                                      \
        }                                                                          \
    }                                                                              \
    SDFC_NEXT;
#include "compiler/ir/opcodes.def"
#undef OP
#if !defined(__GNUC__)
        }
#endif
#undef SDFC_NEXT
#undef SDFC_CASE
}

void Evaluator::eval(const float* x, const float* y, const float* z, int n, float time) {
    eval_code(program_->code.data(), program_->code.size(), x, y, z, n, time);
}

void Evaluator::eval_code(const Instr* code, size_t count, const float* x, const float* y, const float* z, int n,
                          float time) {
    if (n <= 0) return;
    const int m = (n + kGroup - 1) / kGroup * kGroup;  // lanes computed
    const Instr* end = code + count;
    if (m == kBatch) run<true>(code, end, regs_, x, y, z, n, m, time);
    else run<false>(code, end, regs_, x, y, z, n, m, time);
}

float Evaluator::eval1(float x, float y, float z, float time) {
    eval(&x, &y, &z, 1, time);
    return output(0)[0];
}

}  // namespace sdfc
