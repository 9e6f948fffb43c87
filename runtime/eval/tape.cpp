// Tape construction and def links (see tape.hpp).
#include "runtime/eval/tape.hpp"

#include <algorithm>

namespace sdfc {

Tape Tape::from(const Program& p, int output) {
    Tape t;
    t.code = p.code;
    t.out = p.outputs.at(static_cast<size_t>(output));
    t.recount();
    t.num_regs = std::max(t.num_regs, p.num_regs);
    t.link();
    return t;
}

void Tape::recount() {
    uint32_t regs = uint32_t(out) + 1, ch = 0;
    for (const Instr& in : code) {
        regs = std::max<uint32_t>(regs, uint32_t(in.out) + 1);
        ch += is_choice_op(in.op);
    }
    num_regs = regs;
    choices = ch;
}

void Tape::link() {
    const size_t n = code.size();
    links.resize(n);
    thread_local std::vector<uint32_t> last;
    last.assign(std::max<uint32_t>(num_regs, uint32_t(out) + 1), kNone);
    const size_t nregs = last.size();
    bool regs_ok = true;
    if (!well_formed)
        for (const Instr& in : code) regs_ok &= (in.out < nregs) & (in.a < nregs) & (in.b < nregs) & (in.c < nregs);
    if (!regs_ok) {
        linked = false;
        return;
    }
    uint32_t sl = 0;
    for (size_t i = 0; i < n; ++i) {
        const Instr& in = code[i];
        Link& l = links[i];
        // Unused operand fields hold some register number: their "def" is never read.
        l.def[0] = last[in.a];
        l.def[1] = last[in.b];
        l.def[2] = last[in.c];
        const uint32_t ch = uint32_t(is_choice_op(in.op));
        l.slot = ch ? sl : kNone;
        sl += ch;
        last[in.out] = uint32_t(i);
    }
    choices = sl;
    out_def = last[out];
    linked = true;
    if (!well_formed) {
        // A tape reading unwritten registers cannot be followed by def links.
        for (size_t i = 0; i < n && linked; ++i)
            for (int j = 0; j < kOpInfo[int(code[i].op)].arity; ++j) linked &= links[i].def[j] != kNone;
        well_formed = linked;
    }
}

namespace {

// Sets `bit` on the ops `passes` accepts whose every use is such an op (with the bit) or the
// output; ops `ignored` accepts do not count as uses. Users come after their operands, so a
// backward walk sees all of an instruction's users before it.
template <class Passes, class Ignored>
void mark_chains(Tape& t, uint8_t bit, Passes passes, Ignored ignored) {
    if (!t.linked || t.out_def == Tape::kNone) return;
    const size_t n = t.code.size();
    std::vector<uint8_t> use(n, 0);  // 1: used only through marked ops (or as the output), 3: its value is needed
    use[t.out_def] = 1;
    for (size_t i = n; i-- > 0;) {
        Instr& in = t.code[i];
        const bool marked = (use[i] & 2) == 0 && passes(in.op);
        in.pad = uint8_t(marked ? (in.pad | bit) : (in.pad & ~bit));
        if (ignored(in.op)) continue;
        for (int j = 0; j < kOpInfo[int(in.op)].arity; ++j) use[t.links[i].def[j]] |= marked ? 1 : 3;
    }
}

}  // namespace

void Tape::mark_sign_only() {
    mark_chains(
        *this, kSignOnly, [](Op op) { return op == Op::Min || op == Op::Max || op == Op::MinI || op == Op::MaxI; },
        [](Op) { return false; });
}

void Tape::mark_min_chains() {
    mark_chains(*this, kMinChain, [](Op op) { return op == Op::Min; }, [](Op op) { return op == Op::Guard; });
}

void Tape::assign(const Instr* c, size_t count, uint16_t out_reg, uint32_t regs) {
    code.assign(c, c + count);
    out = out_reg;
    num_regs = regs;
    linked = false;
    well_formed = true;  // simplify_batch's output
    links.clear();
    out_def = kNone;
}

}  // namespace sdfc
