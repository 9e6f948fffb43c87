#include "runtime/eval/isa.hpp"

#include <atomic>
#include <cstdlib>
#include <cstring>

namespace sdfc {
namespace {

Isa detect() {
#if defined(SDFC_ISA_DISPATCH)
    __builtin_cpu_init();
    // (libgcc's checks include the OS's: XGETBV says the vector registers are saved.)
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
        __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("bmi2") &&
        __builtin_cpu_supports("fma"))
        return Isa::Avx512;
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2")) return Isa::Avx2;
#endif
    return Isa::Baseline;
}

Isa from_environment(Isa best) {
    const char* s = std::getenv("SDFC_ISA");
    Isa want = best;
    if (s && std::strcmp(s, "baseline") == 0) want = Isa::Baseline;
    if (s && std::strcmp(s, "avx2") == 0) want = Isa::Avx2;
    if (s && std::strcmp(s, "avx512") == 0) want = Isa::Avx512;
    return static_cast<int>(want) < static_cast<int>(best) ? want : best;
}

std::atomic<int> g_isa{-1};

}  // namespace

Isa best_isa() {
    static const Isa best = detect();
    return best;
}

Isa current_isa() {
    int v = g_isa.load(std::memory_order_relaxed);
    if (v < 0) {
        v = static_cast<int>(from_environment(best_isa()));
        g_isa.store(v, std::memory_order_relaxed);
    }
    return static_cast<Isa>(v);
}

Isa set_isa(Isa want) {
    const Isa best = best_isa();
    const Isa isa = static_cast<int>(want) < static_cast<int>(best) ? want : best;
    g_isa.store(static_cast<int>(isa), std::memory_order_relaxed);
    return isa;
}

const char* isa_name(Isa isa) {
#if defined(SDFC_NATIVE_BUILD)
    return "native";
#endif
    if (!isa_dispatch()) return "default";  // one kernel, for the compiler's default target
    switch (isa) {
        case Isa::Baseline: return "x86-64";
        case Isa::Avx2: return "avx2";
        case Isa::Avx512: return "avx512";
    }
    return "?";
}

bool isa_dispatch() {
#if defined(SDFC_ISA_DISPATCH)
    return true;
#else
    return false;
#endif
}

}  // namespace sdfc
