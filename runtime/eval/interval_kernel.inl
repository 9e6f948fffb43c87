// The interval evaluator's kernel: included by interval.cpp once per instruction set, each
// copy in its own namespace (runtime/eval/isa.hpp); no include guard on purpose.

// Lanes 0 .. m (a multiple of 16: IntervalEvaluator::eval rounds up) in loops of a constant
// 16 lanes: one AVX-512 vector, two AVX2 or four SSE2 ones, with no remainder loop.
template <class F>
SDFC_IV_INLINE void for_lanes(int m, F f) {
    for (int i0 = 0; i0 < m; i0 += 16) {
        SDFC_IVDEP
        for (int i = i0; i < i0 + 16; ++i) f(i);
    }
}

// One choice op over m lanes; SignOnly: also decided by sign (sign_choice in interval.cpp).
// Operands are read before the output is written: it may share their register.
// Chain: also keeps the operands' intervals (al, ah, bl, bh: 4 rows of m) for
// prune_min_chains.
template <Op O, bool SignOnly, bool Chain>
SDFC_IV_INLINE void choice_op(const Instr& in, float* const L, float* const H, uint8_t* chp, float* cv, uint8_t* unknown,
                              int m) {
    float* rl = L + size_t(in.out) * kIvLanes;
    float* rh = H + size_t(in.out) * kIvLanes;
    const float* al = L + size_t(in.a) * kIvLanes;
    const float* ah = H + size_t(in.a) * kIvLanes;
    const float* bl = L + size_t(in.b) * kIvLanes;
    const float* bh = H + size_t(in.b) * kIvLanes;
    const float* cl = L + size_t(in.c) * kIvLanes;
    const float* chh = H + size_t(in.c) * kIvLanes;
    const float k = in.k;
    for (int i0 = 0; i0 < m; i0 += 16) {
        // Choices and unknown flags as ints, narrowed to bytes after: a loop storing bytes
        // beside floats was vectorised by GCC in 4-lane pieces (measured: 3x slower).
        int cw[16], uw[16];
        SDFC_IVDEP
        for (int i = i0; i < i0 + 16; ++i) {
            int c;
            float lo, hi;
            iv<O>(al[i], ah[i], bl[i], bh[i], cl[i], chh[i], k, lo, hi, c);
            if constexpr (SignOnly) c = sign_choice<O>(c, al[i], ah[i], bl[i], bh[i], k);
            if constexpr (Chain) {
                cv[i] = al[i];
                cv[m + i] = ah[i];
                cv[2 * m + i] = bl[i];
                cv[3 * m + i] = bh[i];
                uw[i - i0] = (al[i] != al[i]) | (ah[i] != ah[i]) | (bl[i] != bl[i]) | (bh[i] != bh[i]);
            }
            rl[i] = lo;
            rh[i] = hi;
            cw[i - i0] = c;
        }
        for (int i = 0; i < 16; ++i) chp[i0 + i] = uint8_t(cw[i]);
        if constexpr (Chain)
            for (int i = 0; i < 16; ++i) unknown[i0 + i] |= uint8_t(uw[i]);
    }
}

// M: the lane count when fixed at compile time (0: m_rt), so that each op is a fixed run
// of vector instructions without a loop's set-up.
template <int M>
void run_m(const TapeView& t, float* const L, float* const H, uint8_t* chp, float* cv, uint8_t* unknown, const float* xlo,
           const float* xhi, const float* ylo, const float* yhi, const float* zlo, const float* zhi, int n, int m_rt, float time) {
    const int m = M ? M : m_rt;
    auto input = [&](const Instr& in, const float* l, const float* h) {
        float* rl = L + size_t(in.out) * kIvLanes;
        float* rh = H + size_t(in.out) * kIvLanes;
        for (int i = 0; i < m; ++i) {
            int j = i < n ? i : n - 1;
            rl[i] = l[j];
            rh[i] = h[j];
        }
    };
    for (const Instr& in : std::span(t.code, t.len)) {
        float* rl = L + size_t(in.out) * kIvLanes;
        float* rh = H + size_t(in.out) * kIvLanes;
        const float* al = L + size_t(in.a) * kIvLanes;
        const float* ah = H + size_t(in.a) * kIvLanes;
        const float* bl = L + size_t(in.b) * kIvLanes;
        const float* bh = H + size_t(in.b) * kIvLanes;
        const float* cl = L + size_t(in.c) * kIvLanes;
        const float* chh = H + size_t(in.c) * kIvLanes;
        const float k = in.k;
        switch (in.op) {
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl)                                                    \
    case Op::name:                                                                          \
        if constexpr (Op::name == Op::VarX) input(in, xlo, xhi);                            \
        else if constexpr (Op::name == Op::VarY) input(in, ylo, yhi);                       \
        else if constexpr (Op::name == Op::VarZ) input(in, zlo, zhi);                       \
        else if constexpr (Op::name == Op::Time) {                                          \
            std::fill_n(rl, m, time);                                                       \
            std::fill_n(rh, m, time);                                                       \
        } else {                                                                            \
            if constexpr (is_choice_op(Op::name)) {                                         \
                if (cv && is_chain_min(in))                                                 \
                    choice_op<Op::name, false, true>(in, L, H, chp, cv, unknown, m);        \
                else if (in.pad & kSignOnly)                                                \
                    choice_op<Op::name, true, false>(in, L, H, chp, cv, unknown, m);        \
                else                                                                        \
                    choice_op<Op::name, false, false>(in, L, H, chp, cv, unknown, m);       \
                chp += m;                                                                   \
                if (cv) cv += 4 * m;                                                        \
            } else {                                                                        \
                for_lanes(m, [&](int i) SDFC_IV_LAMBDA {                                    \
                    int c;                                                                  \
                    float lo, hi;                                                           \
                    iv<Op::name>(al[i], ah[i], bl[i], bh[i], cl[i], chh[i], k, lo, hi, c);  \
                    rl[i] = lo;                                                             \
                    rh[i] = hi;                                                             \
                });                                                                         \
            }                                                                               \
        }                                                                                   \
        break;
#include "compiler/ir/opcodes.def"
#undef OP
        }
    }
}

// 16 and 64 lanes, the 2D quadtree's 4 x 4 and 8 x 8 children (and the tape tree's 64),
// have their own copies: prospero.vm took 0.965x the time with them.
void run(const TapeView& t, float* const L, float* const H, uint8_t* chp, float* cv, uint8_t* unknown, const float* xlo,
         const float* xhi, const float* ylo, const float* yhi, const float* zlo, const float* zhi, int n, int m, float time) {
    if (m == 16) run_m<16>(t, L, H, chp, cv, unknown, xlo, xhi, ylo, yhi, zlo, zhi, n, m, time);
    else if (m == 64) run_m<64>(t, L, H, chp, cv, unknown, xlo, xhi, ylo, yhi, zlo, zhi, n, m, time);
    else run_m<0>(t, L, H, chp, cv, unknown, xlo, xhi, ylo, yhi, zlo, zhi, n, m, time);
}
