// The batch VM's kernel: included by vm.cpp once per instruction set, each copy in its own
// namespace (runtime/eval/isa.hpp); no include guard on purpose.

// One pass over the program with the lane count M known at compile time when FULL (the
// loops unroll completely) or given at run time (m, a multiple of kGroup) otherwise.
// Dispatch is a computed goto with one indirect jump per handler (GCC/clang), which the
// branch predictor learns per opcode, or a switch elsewhere.
template <bool FULL>
inline void run(const Instr* code, const Instr* end, float* base, const float* x, const float* y,
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

void run_full(const Instr* code, const Instr* end, float* base, const float* x, const float* y, const float* z, int n,
              int m, float time) {
    run<true>(code, end, base, x, y, z, n, m, time);
}
void run_part(const Instr* code, const Instr* end, float* base, const float* x, const float* y, const float* z, int n,
              int m, float time) {
    run<false>(code, end, base, x, y, z, n, m, time);
}
