// The sweep's kernel (SweepVM in runtime/eval/vm.hpp): included by vm.cpp once per
// instruction set after vm_kernel.inl, in the same namespace; no include guard on purpose.
//
// One walk over the parent tape; each instruction runs for every lane that needs it, one
// lane's kBatch points after the other, each lane in its own register file (base[j]). A
// decided choice is what simplify_batch's trace makes of it for that lane: a copy of the
// winner (nothing when it is already in place) or, for an immediate, a constant. Every op
// computes exactly as the VM's handler for it does. A Guard never skips: skipping changes no
// float (vm_kernel.inl), so running its region through gives the same values.

// The lanes whose choice byte in a slot's row equals v: one compare of the row where the
// copy has AVX-512BW (SDFC_SWEEP_BW, set by vm.cpp), else tape.hpp's.
inline uint64_t sweep_lanes(const uint8_t* row, uint8_t v) {
#if SDFC_SWEEP_BW
    return _mm512_cmpeq_epi8_mask(_mm512_loadu_si512(row), _mm512_set1_epi8(char(v)));
#else
    return choice_lanes(row, v);
#endif
}

void sweep(const Instr* code, const Tape::Link* links, size_t n, const uint64_t* need, uint64_t group, const uint8_t* choices, int stride,
           float* const* base, const float* const* xs, const float* const* ys, const float* const* zs, float time) {
    alignas(64) static const float zeros[kBatch] = {};
    auto copy = [](float* R, const float* A) {
        SDFC_IVDEP
        for (int i = 0; i < kBatch; ++i) R[i] = A[i];
    };
    for (size_t at = 0; at < n; ++at) {
        const uint64_t m = need[at] & group;
        if (!m) continue;
        const Instr* ip = code + at;
        const size_t out = size_t(ip->out) * kBatch;
        uint64_t run = m;
        if (const uint32_t sl = links[at].slot; sl != Tape::kNone) {
            const uint8_t* row = choices + size_t(sl) * size_t(stride);
            const uint64_t ca = m & sweep_lanes(row, kChoiceA), cb = m & sweep_lanes(row, kChoiceB);
            const uint64_t cc = ip->op == Op::Select ? m & sweep_lanes(row, kChoiceC) : 0;
            run = m & ~(ca | cb | cc);
            if (ip->a != ip->out)
                for (uint64_t r = ca; r; r &= r - 1) copy(base[__builtin_ctzll(r)] + out, base[__builtin_ctzll(r)] + size_t(ip->a) * kBatch);
            if (ip->op == Op::MinI || ip->op == Op::MaxI) {
                for (uint64_t r = cb; r; r &= r - 1) std::fill_n(base[__builtin_ctzll(r)] + out, kBatch, ip->k);
            } else if (ip->b != ip->out) {
                for (uint64_t r = cb; r; r &= r - 1) copy(base[__builtin_ctzll(r)] + out, base[__builtin_ctzll(r)] + size_t(ip->b) * kBatch);
            }
            if (ip->c != ip->out)
                for (uint64_t r = cc; r; r &= r - 1) copy(base[__builtin_ctzll(r)] + out, base[__builtin_ctzll(r)] + size_t(ip->c) * kBatch);
            if (!run) continue;
        }
        [[maybe_unused]] const size_t oa = size_t(ip->a) * kBatch, ob = size_t(ip->b) * kBatch, oc = size_t(ip->c) * kBatch;
        [[maybe_unused]] const float k = ip->k;
        switch (ip->op) {
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl)                                     \
    case Op::name:                                                                   \
        for (uint64_t r = run; r; r &= r - 1) {                                      \
            const int j = __builtin_ctzll(r);                                        \
            float* R = base[j] + out;                                                \
            [[maybe_unused]] const float* A = base[j] + oa;                          \
            [[maybe_unused]] const float* B = base[j] + ob;                          \
            [[maybe_unused]] const float* C = base[j] + oc;                          \
            if constexpr (Op::name == Op::VarX) copy(R, xs[j]);                      \
            else if constexpr (Op::name == Op::VarY) copy(R, ys[j]);                 \
            else if constexpr (Op::name == Op::VarZ) copy(R, zs ? zs[j] : zeros);    \
            else if constexpr (Op::name == Op::Time) std::fill_n(R, kBatch, time);   \
            else if constexpr (Op::name == Op::Guard) std::fill_n(R, kBatch, om::kSkipped); \
            else if constexpr (vmath::kVector<Op::name>) {                           \
                vmath::apply<Op::name>(R, A, B, k, kBatch);                          \
            } else {                                                                 \
                SDFC_IVDEP                                                           \
                for (int i = 0; i < kBatch; ++i) {                                   \
                    [[maybe_unused]] const float a = A[i];                           \
                    [[maybe_unused]] const float b = B[i];                           \
                    [[maybe_unused]] const float c = C[i];                           \
                    R[i] = (sem);                                                    \
                }                                                                    \
            }                                                                        \
        }                                                                            \
        break;
#include "compiler/ir/opcodes.def"
#undef OP
        }
    }
}
