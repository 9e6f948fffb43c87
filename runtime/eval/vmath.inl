// The batch VM's transcendental ops a vector at a time: SLEEF's vector members of the family
// compiler/ir/op_math.hpp's scalar functions come from, which return the same bits, so the VM
// stays bit for bit the scalar reference. SDFC_VMATH_LANES (vm.cpp) is the vector width of
// the instruction set the copy is compiled for; 1 turns this off (the kernel's lane loop
// calls the scalar functions). Included by vm.cpp once per instruction set before
// vm_kernel.inl, in the same namespace; no include guard on purpose.
namespace vmath {

#if SDFC_VMATH_LANES == 16
using V = __m512;
inline V load(const float* p) { return _mm512_loadu_ps(p); }
inline void store(float* p, V v) { _mm512_storeu_ps(p, v); }
inline V splat(float k) { return _mm512_set1_ps(k); }
#define SDFC_VMATH_FN(f) Sleef_cinz_##f##16_u10avx512fnofma
#elif SDFC_VMATH_LANES == 8
using V = __m256;
inline V load(const float* p) { return _mm256_loadu_ps(p); }
inline void store(float* p, V v) { _mm256_storeu_ps(p, v); }
inline V splat(float k) { return _mm256_set1_ps(k); }
#define SDFC_VMATH_FN(f) Sleef_cinz_##f##8_u10avx
#elif SDFC_VMATH_LANES == 4
using V = __m128;
inline V load(const float* p) { return _mm_loadu_ps(p); }
inline void store(float* p, V v) { _mm_storeu_ps(p, v); }
inline V splat(float k) { return _mm_set1_ps(k); }
#define SDFC_VMATH_FN(f) Sleef_cinz_##f##4_u10sse2
#endif

#if SDFC_VMATH_LANES > 1
// (sleef.h declares these only where the compiler's flags enable the instruction set; here
// it is enabled by the copy's target pragma.)
extern "C" {
V SDFC_VMATH_FN(expf)(V);
V SDFC_VMATH_FN(logf)(V);
V SDFC_VMATH_FN(sinf)(V);
V SDFC_VMATH_FN(cosf)(V);
V SDFC_VMATH_FN(tanf)(V);
V SDFC_VMATH_FN(asinf)(V);
V SDFC_VMATH_FN(acosf)(V);
V SDFC_VMATH_FN(atanf)(V);
V SDFC_VMATH_FN(atan2f)(V, V);
V SDFC_VMATH_FN(powf)(V, V);
}
#endif

template <Op O>
inline constexpr bool kVector = SDFC_VMATH_LANES > 1 &&
                                (O == Op::Exp || O == Op::Log || O == Op::Sin || O == Op::Cos || O == Op::Tan ||
                                 O == Op::Asin || O == Op::Acos || O == Op::Atan || O == Op::Atan2 || O == Op::Pow ||
                                 O == Op::PowI);

// R = O(A, B or k) over lanes [0, m) rounded up to whole vectors (within the batch: the
// extra lanes compute on stale but harmless values, as the kernel's groups do).
template <Op O>
inline void apply(float* R, const float* A, const float* B, float k, int m) {
#if SDFC_VMATH_LANES > 1
    constexpr int W = SDFC_VMATH_LANES;
    static_assert(kBatch % W == 0);
    const int mw = (m + W - 1) / W * W;
    alignas(64) float clamped[kBatch];
    const float* a = A;
    if constexpr (O == Op::Asin || O == Op::Acos) {
        SDFC_IVDEP
        for (int i = 0; i < mw; ++i) clamped[i] = om::clamp1(A[i]);  // as the semantics column
        a = clamped;
    }
    for (int i = 0; i < mw; i += W) {
        const V x = load(a + i);
        V r;
        if constexpr (O == Op::Exp) r = SDFC_VMATH_FN(expf)(x);
        else if constexpr (O == Op::Log) r = SDFC_VMATH_FN(logf)(x);
        else if constexpr (O == Op::Sin) r = SDFC_VMATH_FN(sinf)(x);
        else if constexpr (O == Op::Cos) r = SDFC_VMATH_FN(cosf)(x);
        else if constexpr (O == Op::Tan) r = SDFC_VMATH_FN(tanf)(x);
        else if constexpr (O == Op::Asin) r = SDFC_VMATH_FN(asinf)(x);
        else if constexpr (O == Op::Acos) r = SDFC_VMATH_FN(acosf)(x);
        else if constexpr (O == Op::Atan) r = SDFC_VMATH_FN(atanf)(x);
        else if constexpr (O == Op::Atan2) r = SDFC_VMATH_FN(atan2f)(x, load(B + i));
        else if constexpr (O == Op::Pow) r = SDFC_VMATH_FN(powf)(x, load(B + i));
        else r = SDFC_VMATH_FN(powf)(x, splat(k));  // PowI
        store(R + i, r);
    }
#else
    (void)R, (void)A, (void)B, (void)k, (void)m;
#endif
}

#undef SDFC_VMATH_FN
}  // namespace vmath
