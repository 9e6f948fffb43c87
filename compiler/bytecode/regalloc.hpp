// Register allocation, the one policy of every tape: codegen (forward over the SSA
// order, compiler/bytecode/codegen.cpp) and tape simplification (backward from the
// output, runtime/eval/simplify.cpp). Registers come from a stack of free ones, the
// latest freed first, else a new one; a value's register is freed at its last use before
// the result of that instruction takes one, so the result may share a dying operand's
// register (the lane-wise evaluators allow it). Inline: simplification calls it per
// instruction in its inner loops.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "compiler/bytecode/program.hpp"

namespace sdfc {

class RegPool {
public:
    static constexpr uint32_t kMaxRegs = 0xFFFF;  // register numbers are 16 bits

    // `stack` grows to `max_free`: at least the registers ever free at once (the number of
    // values allocated is always enough).
    RegPool(std::vector<uint16_t>& stack, size_t max_free) {
        if (stack.size() < max_free) stack.resize(max_free);
        free_ = stack.data();
    }

    uint16_t alloc() { return nfree_ ? free_[--nfree_] : uint16_t(next_++); }
    void release(uint16_t r) { free_[nfree_++] = r; }
    // The next alloc() needs a new register and none is left.
    bool exhausted() const { return nfree_ == 0 && next_ >= kMaxRegs; }
    uint32_t used() const { return next_ > 0 ? next_ : 1; }  // registers a tape needs (at least one)

private:
    uint16_t* free_;
    size_t nfree_ = 0;
    uint32_t next_ = 0;
};

// One instruction of a backward scan: its result register X is freed (the value is dead
// above its definition), then the operands take theirs: use(j) binds operand j, allocating
// at its last use, the first one met walking backwards. Operand a goes first, so it gets X
// when it dies here: a later trace of the tape then needs no copy when a wins a choice
// (the common case: the accumulated side of a min/max chain).
template <class Use>
inline Instr emit_backward(RegPool& pool, const Instr& in, uint16_t X, Use&& use) {
    pool.release(X);
    Instr e{in.op};
    e.pad = in.pad;
    e.out = X;
    e.k = in.k;
    const int ar = kOpInfo[int(in.op)].arity;
    if (ar >= 1) e.a = use(0);
    if (ar >= 2) e.b = use(1);
    if (ar >= 3) e.c = use(2);
    return e;
}

}  // namespace sdfc
