// Start-up tuning of the heap (see common.hpp, use_big_pages).
#include "cli/common.hpp"

#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>

namespace sdfc::cli {

// A big script's check spends most of its time in first-touch page faults (bench/run row 6:
// 14,500 faults, 12 us each on a virtual machine, for the AST, the graph and the programs).
// The calling thread's heap is marked for transparent huge pages where the kernel offers
// them (madvise mode, Debian's default): one fault per 2 MB instead of per 4 KB, as glibc's
// tunable glibc.malloc.hugetlb=1 would do. Allocations up to 32 MB stay in that heap (no
// mmap of their own), and its free top is not trimmed below 128 MB. Untouched pages cost
// nothing; other threads' arenas are left as they are.
void use_big_pages() {
#if defined(__GLIBC__) && defined(MADV_HUGEPAGE) && !defined(__SANITIZE_ADDRESS__)
    constexpr size_t kHuge = size_t(2) << 20;
    // glibc's non-main arenas are heaps of at most 64 MB (HEAP_MAX_SIZE on 64-bit), aligned
    // to their size; the main arena is the brk heap, given a 64 MB top pad here.
    constexpr size_t kArenaHeap = size_t(64) << 20;
    mallopt(M_MMAP_THRESHOLD, int(kArenaHeap / 2));
    mallopt(M_TRIM_THRESHOLD, int(kArenaHeap * 2));
    mallopt(M_TOP_PAD, int(kArenaHeap));
    void* p = std::malloc(1);
    if (!p) return;
    const uintptr_t at = reinterpret_cast<uintptr_t>(p);
    const uintptr_t brk = reinterpret_cast<uintptr_t>(sbrk(0));
    uintptr_t lo, hi;
    if (at < brk && brk - at < kArenaHeap * 2) {  // the main arena: up to its (padded) top
        lo = (at + kHuge - 1) & ~uintptr_t(kHuge - 1);
        hi = brk & ~uintptr_t(kHuge - 1);
    } else {  // a thread's arena: its whole heap
        lo = at & ~uintptr_t(kArenaHeap - 1);
        hi = lo + kArenaHeap;
    }
    if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);  // a hint: failure is harmless
    std::free(p);
#endif
}

}  // namespace sdfc::cli
