#include "compiler/base/stack.hpp"

#include <pthread.h>

#include <cstdint>

#include "compiler/base/source.hpp"

namespace sdfc {

namespace {

// The lowest usable address of this thread's stack (0 when unknown: no check).
uintptr_t stack_low() {
    thread_local const uintptr_t low = [] {
        pthread_attr_t a;
        if (pthread_getattr_np(pthread_self(), &a) != 0) return uintptr_t(0);
        void* addr = nullptr;
        size_t size = 0;
        int r = pthread_attr_getstack(&a, &addr, &size);
        pthread_attr_destroy(&a);
        return r == 0 ? reinterpret_cast<uintptr_t>(addr) : uintptr_t(0);
    }();
    return low;
}

}  // namespace

bool stack_nearly_exhausted() {
    // Far more than any stage uses between two checks (or to throw and unwind), even
    // with sanitizers' larger frames.
    constexpr uintptr_t kMargin = 512u << 10;
    const uintptr_t low = stack_low();
    const auto here = reinterpret_cast<uintptr_t>(__builtin_frame_address(0));
    return low != 0 && here < low + kMargin;
}

// Sanitizer builds cap the stack of a thread of its own:
// - AddressSanitizer: at most 48 MB. An exception thrown with more than 64 MB of stack in
//   use leaves the stack poisoned (ASan's __asan_handle_no_return gives up), and the
//   unwinding reports false errors.
// - ThreadSanitizer: at most 8 MB. It stops the program ("CHECK failed ... kStackSizeBits")
//   when it records a stack of more than 65,536 frames; 8 MB holds about 40,000 of the
//   parser's (about 200 bytes each).
#if defined(__SANITIZE_ADDRESS__)
#define SDFC_STACK_ASAN 1
#elif defined(__SANITIZE_THREAD__)
#define SDFC_STACK_TSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SDFC_STACK_ASAN 1
#elif __has_feature(thread_sanitizer)
#define SDFC_STACK_TSAN 1
#endif
#endif

size_t max_thread_stack() {
#if defined(SDFC_STACK_ASAN)
    return 48u << 20;
#elif defined(SDFC_STACK_TSAN)
    return 8u << 20;
#else
    return size_t(4) << 30;
#endif
}

namespace {
void* run_function(void* p) {
    (*static_cast<const std::function<void()>*>(p))();
    return nullptr;
}
}  // namespace

bool run_on_new_stack(size_t bytes, const std::function<void()>& fn) {
    pthread_attr_t attr;
    if (pthread_attr_init(&attr) != 0) return false;
    pthread_t t;
    bool started = pthread_attr_setstacksize(&attr, bytes) == 0 &&
                   pthread_create(&t, &attr, run_function, const_cast<std::function<void()>*>(&fn)) == 0;
    pthread_attr_destroy(&attr);
    if (started) pthread_join(t, nullptr);
    return started;
}

void check_stack(Loc loc) {
    if (stack_nearly_exhausted())
        throw CompileError(loc, "nested too deeply: the C++ stack is nearly exhausted (simplify the script, "
                                "or run with a larger stack: ulimit -s)");
}

}  // namespace sdfc
