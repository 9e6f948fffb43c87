#include "runtime/eval/vm.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <new>
#include <utility>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "runtime/eval/isa.hpp"
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

using RunFn = void (*)(const Instr*, const Instr*, const Guard*, float*, const float*, const float*, const float*, int, float);

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

// The kernel for each instruction set the build carries (runtime/eval/isa.hpp), with the
// vector width of its transcendentals (runtime/eval/vmath.inl): the AVX2 copy takes SLEEF's
// AVX functions, as the FMA-free family has no AVX2 member.
#if defined(__AVX512F__)
#define SDFC_VMATH_LANES 16
#elif defined(__AVX__)
#define SDFC_VMATH_LANES 8
#elif defined(__SSE2__)
#define SDFC_VMATH_LANES 4
#else
#define SDFC_VMATH_LANES 1
#endif
#if defined(__AVX512BW__)
#define SDFC_SWEEP_BW 1
#else
#define SDFC_SWEEP_BW 0
#endif
namespace isa_baseline {
#include "runtime/eval/vmath.inl"
#include "runtime/eval/vm_kernel.inl"
#include "runtime/eval/sweep_kernel.inl"
}  // namespace isa_baseline
#undef SDFC_SWEEP_BW
#define SDFC_SWEEP_BW 0
#undef SDFC_VMATH_LANES
#if defined(SDFC_ISA_DISPATCH)
#define SDFC_VMATH_LANES 8
SDFC_ISA_BEGIN_AVX2
namespace isa_avx2 {
#include "runtime/eval/vmath.inl"
#include "runtime/eval/vm_kernel.inl"
#include "runtime/eval/sweep_kernel.inl"
}  // namespace isa_avx2
SDFC_ISA_END
#undef SDFC_VMATH_LANES
#define SDFC_VMATH_LANES 16
SDFC_ISA_BEGIN_AVX512
#undef SDFC_SWEEP_BW
#define SDFC_SWEEP_BW 1
namespace isa_avx512 {
#include "runtime/eval/vmath.inl"
#include "runtime/eval/vm_kernel.inl"
#include "runtime/eval/sweep_kernel.inl"
}  // namespace isa_avx512
SDFC_ISA_END
#undef SDFC_VMATH_LANES
#endif
#undef SDFC_SWEEP_BW

namespace {
// Each instruction set's kernels, by lane count (vm_kernel.inl).
const RunFn* const kKernels[] = {
    isa_baseline::runs.data(),
#if defined(SDFC_ISA_DISPATCH)
    isa_avx2::runs.data(),
    isa_avx512::runs.data(),
#endif
};
using SweepFn = void (*)(const Instr*, const Tape::Link*, size_t, const uint64_t*, uint64_t, const uint8_t*, int, float* const*,
                        const float* const*, const float* const*, const float* const*, float);
const SweepFn kSweeps[] = {
    isa_baseline::sweep,
#if defined(SDFC_ISA_DISPATCH)
    isa_avx2::sweep,
    isa_avx512::sweep,
#endif
};
const RunFn* kernels() {
    const int i = static_cast<int>(current_isa());
    return kKernels[i < int(std::size(kKernels)) ? i : 0];
}
}  // namespace

void BatchVM::eval(const TapeView& t, const float* x, const float* y, const float* z, int n, float time) {
    if (n <= 0) return;
    if (t.num_regs > max_regs_) reserve(t.num_regs);
    const int m = (n + kGroup - 1) / kGroup * kGroup;  // lanes computed
    const Instr* end = t.code + t.len;
    kernels()[m / kGroup - 1](t.code, end, t.guards, regs_, x, y, z, n, time);
}

void SweepVM::eval(const Tape& t, const uint8_t* choices, int stride, const uint64_t* need, uint64_t lanes,
                   const float* const* x, const float* const* y, const float* const* z, float time) {
    const size_t per = size_t(std::max<uint32_t>(t.num_regs, uint32_t(t.out) + 1)) * kBatch;
    const size_t count = size_t(__builtin_popcountll(lanes));
    // As many lanes a pass as max_floats_ holds (at least one): all of them but for tapes
    // of thousands of registers, whose passes then copy their outputs aside.
    const size_t group = std::clamp<size_t>(max_floats_ / per, 1, std::max<size_t>(count, 1));
    if (per * group > size_) {
        storage_ = {alloc_regs(per * group), &free_aligned};
        size_ = per * group;
    }
    if (group < count && !outs_) outs_ = std::make_unique<float[]>(size_t(64) * kBatch);
    const int isa = static_cast<int>(current_isa());
    const auto kernel = kSweeps[isa < int(std::size(kSweeps)) ? isa : 0];
    while (lanes) {
        uint64_t pass = 0;
        size_t q = 0;
        for (uint64_t r = lanes; r && q < group; r &= r - 1) {
            const int j = __builtin_ctzll(r);
            pass |= uint64_t(1) << j;
            base_[j] = storage_.get() + per * q++;
        }
        lanes &= ~pass;
        kernel(t.code.data(), t.links.data(), t.code.size(), need, pass, choices, stride, base_, x, y, z, time);
        for (uint64_t r = pass; r; r &= r - 1) {
            const int j = __builtin_ctzll(r);
            out_[j] = base_[j] + size_t(t.out) * kBatch;
            if (group < count) out_[j] = std::copy_n(out_[j], kBatch, outs_.get() + size_t(j) * kBatch) - kBatch;
        }
    }
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
