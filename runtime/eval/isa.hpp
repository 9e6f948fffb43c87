// Which instruction set the batch kernels (the VM's and the interval evaluator's lane loops)
// run with. The default build targets baseline x86-64 and carries each kernel three times,
// compiled for x86-64, AVX2+FMA and AVX-512 (the kernel's .inl file included once per
// target under `#pragma GCC target`, see SDFC_ISA_BEGIN); the best the CPU has is chosen
// once, at the first evaluation. A -DSDFC_NATIVE=ON build carries one kernel, for its CPU.
#pragma once

namespace sdfc {

enum class Isa : int { Baseline = 0, Avx2 = 1, Avx512 = 2 };
inline constexpr int kIsaCount = 3;

// The kernels evaluations use now: the best the CPU and the build allow, capped by the
// environment variable SDFC_ISA (baseline, avx2 or avx512), for comparisons.
Isa current_isa();
// Sets the kernels (capped by what the CPU and the build allow); returns what it set.
// For tests and benchmarks; evaluations started after it use the new kernels.
Isa set_isa(Isa want);
// The best the CPU and the build allow.
Isa best_isa();
// "x86-64", "avx2", "avx512"; "native" in a -march=native build ("default" in another
// build with one kernel: another compiler or CPU family).
const char* isa_name(Isa isa);
// Whether this build carries kernels per instruction set.
bool isa_dispatch();

}  // namespace sdfc

// Brackets of one kernel's copy for a target (GCC on x86-64 without -march=native). Code
// defined outside, such as the opcode semantics' helpers, inlines into each copy and is
// vectorised for its target there.
#if defined(SDFC_ISA_DISPATCH)
#define SDFC_ISA_BEGIN_AVX2 \
    _Pragma("GCC push_options") _Pragma("GCC target(\"avx,avx2,fma,bmi,bmi2,lzcnt,popcnt,f16c,movbe\")")
#define SDFC_ISA_BEGIN_AVX512                                                                               \
    _Pragma("GCC push_options")                                                                             \
        _Pragma("GCC target(\"avx,avx2,fma,bmi,bmi2,lzcnt,popcnt,f16c,movbe,avx512f,avx512cd,avx512vl,avx512bw,avx512dq\")")
#define SDFC_ISA_END _Pragma("GCC pop_options")
#endif
