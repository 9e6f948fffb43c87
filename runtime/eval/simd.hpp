// Loop hints shared by the lane-wise evaluators (vm.cpp, interval.cpp).
#pragma once

// An op's output register may be one of its operand registers (the allocators reuse a
// dying operand's register), but only lane i is ever read to write lane i, so the lane
// loops carry no dependence: tell the vectoriser, so it neither versions nor falls back
// to scalar code.
#if defined(__clang__)
#define SDFC_IVDEP _Pragma("clang loop vectorize(assume_safety)")
#elif defined(__GNUC__)
#define SDFC_IVDEP _Pragma("GCC ivdep")
#else
#define SDFC_IVDEP
#endif

// The per-lane interval functions must inline into the lane loops for those to vectorise.
#if defined(__GNUC__)
#define SDFC_IV_INLINE __attribute__((always_inline)) inline
#else
#define SDFC_IV_INLINE inline
#endif
// The same for a lambda body passed to a lane loop: `[&](int i) SDFC_IV_LAMBDA { ... }`.
#if defined(__GNUC__)
#define SDFC_IV_LAMBDA __attribute__((always_inline))
#else
#define SDFC_IV_LAMBDA
#endif
