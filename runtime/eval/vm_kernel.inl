// The batch VM's kernel: included by vm.cpp once per instruction set, each copy in its own
// namespace (runtime/eval/isa.hpp); no include guard on purpose.

// Whether every one of the n points is far enough outside guard g's box to skip its region
// (program.hpp Guard): farther than the threshold `thr` by a margin that covers the region's
// rounding errors (its distance is never below the box's in exact arithmetic), so that
// skipping changes no float of the union: the batch VM stays bit for bit the scalar
// reference, which runs through.
SDFC_IV_INLINE bool guard_skips_lane(const Guard& g, float box, float x, float y, float z, float thr) {
    const float ex = std::max(std::max(g.lo[0] - x, x - g.hi[0]), 0.0f);
    const float ey = std::max(std::max(g.lo[1] - y, y - g.hi[1]), 0.0f);
    const float ez = std::max(std::max(g.lo[2] - z, z - g.hi[2]), 0.0f);
    const float e2 = ex * ex + ey * ey + ez * ez;
    const float need = thr + 0x1p-14f * (1.0f + box + std::fabs(x) + std::fabs(y) + std::fabs(z) + std::fabs(thr));
    // NaN, +inf or beyond 1e18 (where the squares could overflow): never skips.
    return need > 0.0f && need < 1e18f && e2 >= need * need;
}
inline bool guard_skips_all(const Guard& g, const float* base, const float* thr, int n) {
    const float* px = base + static_cast<size_t>(g.px) * kBatch;
    const float* py = base + static_cast<size_t>(g.py) * kBatch;
    const float* pz = base + static_cast<size_t>(g.pz) * kBatch;
    const float box = std::max(std::max(std::max(std::fabs(g.lo[0]), std::fabs(g.hi[0])), std::max(std::fabs(g.lo[1]), std::fabs(g.hi[1]))),
                               std::max(std::fabs(g.lo[2]), std::fabs(g.hi[2])));
    // Most regions that run fail at the first point; the rest check every point at once.
    if (!guard_skips_lane(g, box, px[0], py[0], pz[0], thr[0])) return false;
    int fail = 0;
    SDFC_IVDEP
    for (int i = 1; i < n; ++i) fail |= int(!guard_skips_lane(g, box, px[i], py[i], pz[i], thr[i]));
    return fail == 0;
}

// One pass over the program for M lanes (a multiple of kGroup, at most kBatch), a count
// known at compile time: each op is a fixed run of vector instructions without a loop's
// set-up, which dominated the small batches of a window's lanes split by tape-tree leaf (the
// 10,000-sphere grid: 10.7 points a batch; with a kernel per count, 0.87x its time).
// Dispatch is a computed goto with one indirect jump per handler (GCC/clang), which the
// branch predictor learns per opcode, or a switch elsewhere.
#if defined(__GNUC__) && !defined(__clang__)
// (else GCC unrolls a loop of a few fixed lanes into scalar code, which is slower; a full
// batch's loop unrolls into vector code and is faster so)
#define SDFC_NO_UNROLL _Pragma("GCC unroll 1")
#else
#define SDFC_NO_UNROLL
#endif
template <int M>
void run(const Instr* code, const Instr* end, const Guard* guards, float* base, const float* x, const float* y,
         const float* z, int n, float time) {
    constexpr int m = M;
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
        else if constexpr (Op::name == Op::Guard) {                                \
            /* (its out may share the threshold's or the point's register) */      \
            const Guard* g = guards ? &guards[guard_index(*ip)] : nullptr;         \
            const bool skip = g && guard_skips_all(*g, base, A, n);                \
            std::fill_n(R, m, om::kSkipped);                                       \
            if (skip) ip = code + g->end - 1;                                      \
        } else if constexpr (vmath::kVector<Op::name>) {                           \
            vmath::apply<Op::name>(R, A, B, k, m);                                 \
        } else {                                                                   \
            if constexpr (M < kBatch) {                                            \
                SDFC_IVDEP                                                         \
                SDFC_NO_UNROLL                                                     \
                for (int i = 0; i < M; ++i) {                                      \
                    [[maybe_unused]] const float a = A[i];                         \
                    [[maybe_unused]] const float b = B[i];                         \
                    [[maybe_unused]] const float c = C[i];                         \
                    R[i] = (sem);                                                  \
                }                                                                  \
            } else {                                                               \
                SDFC_IVDEP                                                         \
                for (int i = 0; i < m; ++i) {                                      \
                    [[maybe_unused]] const float a = A[i];                         \
                    [[maybe_unused]] const float b = B[i];                         \
                    [[maybe_unused]] const float c = C[i];                         \
                    R[i] = (sem);                                                  \
                }                                                                  \
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

// The kernels by lane count: runs[m / kGroup - 1] runs m lanes.
template <int... G>
constexpr std::array<RunFn, sizeof...(G)> make_runs(std::integer_sequence<int, G...>) {
    return {&run<(G + 1) * kGroup>...};
}
constexpr auto runs = make_runs(std::make_integer_sequence<int, kBatch / kGroup>());
#undef SDFC_NO_UNROLL
