// The C++ stack of the recursive stages: the guard that turns deep input into a diagnostic,
// and threads with a stack of a given size.
#pragma once
#include <cstddef>
#include <functional>

namespace sdfc {

struct Loc;  // compiler/base/source.hpp

// Every recursive stage (parser, interpreter, lowering) calls this once per level: it
// throws CompileError at `loc` when the current thread's C++ stack is nearly used up, so
// input nested deeper than the stack allows is a diagnostic, never a stack overflow,
// whatever the limits (--max-nesting, --max-recursion, --max-shape-depth) are raised to.
void check_stack(Loc loc);
bool stack_nearly_exhausted();  // the test alone (when making the Loc costs something)

// The most stack this build gives a thread of its own: 4 GiB of address space (touched
// only as deep as the input goes), less under sanitizers (see compiler/base/stack.cpp).
size_t max_thread_stack();
// Runs `fn` on a new thread with a stack of `bytes` and waits for it; false (fn not run)
// when no such thread can be made. `fn` must not throw.
bool run_on_new_stack(size_t bytes, const std::function<void()>& fn);

}  // namespace sdfc
