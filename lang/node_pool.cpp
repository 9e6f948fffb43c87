// The allocator of AST nodes: Expr and Stmt (lang/ast.hpp) declare operator new/delete,
// defined here over per-thread pools.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <new>
#include <utility>
#include <vector>

#include "lang/ast.hpp"

namespace sdfc::ast {
namespace {

// Expr and Stmt nodes (ast.hpp) come from per-thread pools of same-size slots: a pool hands
// out freed slots last-in first-out (kept in an array, so reuse reads no freed memory), else
// the next slot of its current chunk. Memory is never given back to the system, so parsing
// again reuses it without page faults (first-touch faults dominate a big script's parse).
// A thread that exits leaves its slots in a global depot for other threads; all chunks are
// on a global list, so leak checkers see them as reachable. Under AddressSanitizer nodes use
// the ordinary heap, so it still finds use-after-free.
#if defined(__SANITIZE_ADDRESS__)
#define SDFC_NODE_POOL 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SDFC_NODE_POOL 0
#endif
#endif
#ifndef SDFC_NODE_POOL
#define SDFC_NODE_POOL 1
#endif

#if SDFC_NODE_POOL
struct PoolChunk {
    PoolChunk* next;
};
constinit std::atomic<PoolChunk*> all_chunks{nullptr};

// A thread's pool for one slot size. Plain data (so it stays usable while the thread's other
// thread_locals are destroyed); PoolExit hands its slots over to the depot at thread exit.
template <size_t Size>
struct NodePool {
    static constexpr size_t kHeader = alignof(std::max_align_t);
    static_assert(sizeof(PoolChunk) <= kHeader && Size % alignof(std::max_align_t) == 0);
    static constexpr size_t kFirstChunk = 64 << 10, kMaxChunk = 1 << 20;

    void** free = nullptr;  // freed slots, reused first-in first-out: free[head, count); malloc'ed
    size_t head = 0, count = 0, cap = 0;
    char* next = nullptr;   // the unused rest of the current chunk
    char* end = nullptr;
    size_t chunk_bytes = kFirstChunk;
    bool exited = false;    // after thread exit, slots come from and go to the depot

    // Slots of exited threads. Never destroyed: threads (and static destructors) may free
    // nodes after main() returned.
    struct Depot {
        std::mutex mutex;
        std::vector<void*> slots;
    };
    static Depot& depot() {
        static Depot* d = new Depot;
        return *d;
    }

    void* get() {
        if (head != count) return take_free();
        if (next != end) return std::exchange(next, next + Size);
        return refill();
    }
    // Oldest first: a tree is freed in about the order it was allocated, so the next parse
    // gets its slots in about address order too.
    void* take_free() {
        void* p = free[head++];
        if (head == count) head = count = 0;
        return p;
    }
    void put(void* p) noexcept {
        if (count == cap && head != 0) {
            std::memmove(static_cast<void*>(free), static_cast<void*>(free + head), (count - head) * sizeof(void*));
            count -= head;
            head = 0;
        }
        if (count == cap && !grow()) {
            to_depot(p);
            return;
        }
        free[count++] = p;
    }

    bool grow() noexcept {
        if (exited) return false;
        size_t n = cap ? 2 * cap : 4096;
        void* f = std::realloc(static_cast<void*>(free), n * sizeof(void*));
        if (!f) return false;
        free = static_cast<void**>(f);
        cap = n;
        return true;
    }
    static void to_depot(void* p) noexcept {
        Depot& d = depot();
        std::lock_guard<std::mutex> lock(d.mutex);
        try {
            d.slots.push_back(p);
        } catch (...) {  // out of memory: the slot is lost, not the program
        }
    }
    void* refill();
    void hand_over() noexcept {
        Depot& d = depot();
        std::lock_guard<std::mutex> lock(d.mutex);
        try {
            d.slots.insert(d.slots.end(), free + head, free + count);
            for (; next != end; next += Size) d.slots.push_back(next);
        } catch (...) {
        }
        std::free(static_cast<void*>(free));
        free = nullptr;
        head = count = cap = 0;
        next = end = nullptr;
        exited = true;
    }
};

constexpr size_t slot_size(size_t n) { return (n + 15) / 16 * 16; }
using ExprPool = NodePool<slot_size(sizeof(Expr))>;
using StmtPool = NodePool<slot_size(sizeof(Stmt))>;
thread_local constinit ExprPool expr_pool;
thread_local constinit StmtPool stmt_pool;

struct PoolExit {
    ~PoolExit() {
        expr_pool.hand_over();
        stmt_pool.hand_over();
    }
};
thread_local PoolExit pool_exit;

template <size_t Size>
void* NodePool<Size>::refill() {
    static_cast<void>(&pool_exit);  // registers the hand-over at this thread's exit
    {
        Depot& d = depot();
        std::lock_guard<std::mutex> lock(d.mutex);
        if (!d.slots.empty()) {
            if (exited) {
                void* p = d.slots.back();
                d.slots.pop_back();
                return p;
            }
            while (!d.slots.empty() && (count < cap || grow()) && count < 4096) {
                free[count++] = d.slots.back();
                d.slots.pop_back();
            }
        }
    }
    if (head != count) return take_free();
    if (exited) return ::operator new(Size);  // a slot of its own, given to the depot when freed
    char* mem = static_cast<char*>(::operator new(chunk_bytes));
    auto* chunk = reinterpret_cast<PoolChunk*>(mem);
    chunk->next = all_chunks.load(std::memory_order_relaxed);
    while (!all_chunks.compare_exchange_weak(chunk->next, chunk, std::memory_order_release, std::memory_order_relaxed)) {
    }
    next = mem + kHeader;
    end = next + (chunk_bytes - kHeader) / Size * Size;
    chunk_bytes = std::min(2 * chunk_bytes, kMaxChunk);
    return std::exchange(next, next + Size);
}
#endif

}  // namespace

#if SDFC_NODE_POOL
void* Expr::operator new(std::size_t size) { return size == sizeof(Expr) ? expr_pool.get() : ::operator new(size); }
void Expr::operator delete(void* p, std::size_t size) noexcept {
    if (!p) return;
    if (size == sizeof(Expr))
        expr_pool.put(p);
    else
        ::operator delete(p);
}
void* Stmt::operator new(std::size_t size) { return size == sizeof(Stmt) ? stmt_pool.get() : ::operator new(size); }
void Stmt::operator delete(void* p, std::size_t size) noexcept {
    if (!p) return;
    if (size == sizeof(Stmt))
        stmt_pool.put(p);
    else
        ::operator delete(p);
}
#else
void* Expr::operator new(std::size_t size) { return ::operator new(size); }
void Expr::operator delete(void* p, std::size_t) noexcept { ::operator delete(p); }
void* Stmt::operator new(std::size_t size) { return ::operator new(size); }
void Stmt::operator delete(void* p, std::size_t) noexcept { ::operator delete(p); }
#endif

}  // namespace sdfc::ast
