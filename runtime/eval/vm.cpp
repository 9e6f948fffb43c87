#include "runtime/eval/vm.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>

#include "runtime/eval/simd.hpp"

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

}  // namespace

BatchVM::BatchVM(uint32_t max_regs)
    : max_regs_(std::max<uint32_t>(max_regs, 1)),
      storage_(alloc_regs(static_cast<size_t>(max_regs_) * kBatch), &free_aligned),
      regs_(storage_.get()) {}

void BatchVM::reserve(uint32_t regs) {
    if (regs <= max_regs_) return;
    storage_.reset(alloc_regs(static_cast<size_t>(regs) * kBatch));
    regs_ = storage_.get();
    max_regs_ = regs;
}

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
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl) &&L_##name,
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
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl)                                           \
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

void BatchVM::eval(const TapeView& t, const float* x, const float* y, const float* z, int n, float time) {
    if (n <= 0) return;
    if (t.num_regs > max_regs_) reserve(t.num_regs);
    const int m = (n + kGroup - 1) / kGroup * kGroup;  // lanes computed
    const Instr* end = t.code + t.len;
    if (m == kBatch) run<true>(t.code, end, regs_, x, y, z, n, m, time);
    else run<false>(t.code, end, regs_, x, y, z, n, m, time);
}

void sample_batch(const Program& p, const float* x, const float* y, const float* z, size_t n, float time, float* out) {
    if (p.outputs.empty()) return;
    Evaluator ev(p);
    for (size_t i = 0; i < n; i += kBatch) {
        const int m = static_cast<int>(std::min<size_t>(kBatch, n - i));
        ev.eval(x + i, y + i, z + i, m, time);
        std::copy_n(ev.output(0), m, out + i);
    }
}

}  // namespace sdfc
