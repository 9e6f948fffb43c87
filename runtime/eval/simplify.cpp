// Tape simplification (see simplify.hpp): one box at a time (simplify) or many at once
// (simplify_batch). Registers are re-allocated backwards from the output with the shared
// policy of compiler/bytecode/regalloc.hpp.
#include "runtime/eval/simplify.hpp"

#include <algorithm>
#include <iterator>

#include "compiler/bytecode/regalloc.hpp"

namespace sdfc {

void simplify(const Tape& parent, const uint8_t* choices, int stride, int lane, Tape& out, SimplifyScratch& s) {
    const size_t n = parent.code.size();
    out.code.clear();
    out.linked = false;
    out.well_formed = false;
    out.out = 0;
    out.num_regs = 1;
    out.choices = 0;
    if (n == 0 || parent.out_def == Tape::kNone || !parent.linked) {
        // The output is never written, or the tape reads unwritten registers: keep it as is.
        out.code = parent.code;
        out.out = parent.out;
        out.num_regs = parent.num_regs;
        out.choices = parent.choices;
        return;
    }
    const size_t words = (n + 63) / 64;
    s.live.assign(words, 0);
    if (s.bind.size() < n) s.bind.resize(n);
    if (s.rev.size() < n + 1) s.rev.resize(n + 1);
    Instr* rev = s.rev.data();
    size_t nrev = 0;
    RegPool pool(s.free_regs, n + 1);
    uint32_t nch = 0;
    uint64_t* live = s.live.data();
    uint16_t* bind = s.bind.data();
    const uint8_t* cp = choices + lane;
    const Instr* code = parent.code.data();
    const Tape::Link* links = parent.links.data();
    // A decided choice op whose winner is a register is skipped: its users read the winner
    // directly (following chains of them).
    auto chase = [&](uint32_t d) -> uint32_t {
        for (;;) {
            const uint32_t sl = links[d].slot;
            if (sl == Tape::kNone) return d;
            const uint8_t ch = cp[size_t(sl) * size_t(stride)];
            if (ch == kChoiceBoth) return d;
            if (ch == kChoiceB && (code[d].op == Op::MinI || code[d].op == Op::MaxI)) return d;  // becomes a Const
            d = links[d].def[ch - 1];
        }
    };
    {
        const uint32_t o = chase(parent.out_def);
        live[o >> 6] |= uint64_t(1) << (o & 63);
        bind[o] = pool.alloc();
    }
    // The register holding the value of instruction d, allocating one at its last use
    // (the first met walking backwards).
    auto use = [&](uint32_t d) -> uint16_t {
        d = chase(d);
        uint64_t& w = live[d >> 6];
        const uint64_t bit = uint64_t(1) << (d & 63);
        if (!(w & bit)) {
            w |= bit;
            bind[d] = pool.alloc();
        }
        return bind[d];
    };
    for (size_t w = words; w-- > 0;) {
        uint64_t word;
        while ((word = live[w]) != 0) {
            const int b = 63 - __builtin_clzll(word);
            live[w] = word & ~(uint64_t(1) << b);
            const uint32_t i = uint32_t(w * 64 + size_t(b));
            const Instr in = code[i];
            const Tape::Link& l = links[i];
            const uint16_t X = bind[i];
            if (l.slot != Tape::kNone) {
                if (cp[size_t(l.slot) * size_t(stride)] != kChoiceBoth) {
                    // MinI/MaxI whose immediate wins (chase() stops there): a constant.
                    pool.release(X);
                    Instr c{Op::Const};
                    c.out = X;
                    c.k = in.k;
                    rev[nrev++] = c;
                    continue;
                }
                ++nch;
            }
            rev[nrev++] = emit_backward(pool, in, X, [&](int j) { return use(l.def[j]); });
        }
    }
    out.code.assign(std::make_reverse_iterator(rev + nrev), std::make_reverse_iterator(rev));
    out.out = 0;  // the output was bound first
    out.num_regs = pool.used();
    out.choices = nch;
    out.well_formed = true;
    out.link();  // ready to be simplified further
}

namespace {

// The lanes (bits of `lanes`) in which each instruction's value is needed: mask[i]. One
// backward pass over the parent (linked, with an output), following only the winners of
// decided choices.
void need_masks(const Tape& parent, const uint8_t* choices, int stride, uint64_t lanes, std::vector<uint64_t>& mask) {
    const size_t n = parent.code.size();
    if (mask.size() < n) mask.resize(n);
    uint64_t* need = mask.data();
    std::fill_n(need, n, uint64_t(0));
    need[parent.out_def] = lanes;
    const Instr* code = parent.code.data();
    const Tape::Link* links = parent.links.data();
    for (size_t i = n; i-- > 0;) {
        const uint64_t m = need[i];
        if (!m) continue;
        const Instr& in = code[i];
        const Tape::Link& l = links[i];
        const int ar = kOpInfo[int(in.op)].arity;
        if (l.slot == Tape::kNone) {
            if (ar > 0) need[l.def[0]] |= m;
            if (ar > 1) need[l.def[1]] |= m;
            if (ar > 2) need[l.def[2]] |= m;
            continue;
        }
        const uint8_t* row = choices + size_t(l.slot) * size_t(stride);
        const uint64_t ca = choice_lanes(row, kChoiceA), cb = choice_lanes(row, kChoiceB);
        const uint64_t cc = in.op == Op::Select ? choice_lanes(row, kChoiceC) : 0;
        const uint64_t both = m & ~(ca | cb | cc);
        need[l.def[0]] |= in.op == Op::Select ? both : (m & (ca | both));
        if (in.op == Op::Min || in.op == Op::Max || in.op == Op::Select) need[l.def[1]] |= m & (cb | both);
        if (in.op == Op::Select) need[l.def[2]] |= m & (cc | both);
    }
}

// Lane j's compact tape from its live instructions list[0 .. count) (parent indices,
// ascending), walked backwards: registers re-allocated (linear scan; an op's output may
// share a dying operand's register, which the lane-wise VM allows); a decided choice op's
// winner takes over its output register (no instruction), or is copied when it stays
// needed elsewhere; an immediate that wins becomes a constant. Written backwards, ending
// just before `end`; returns the instruction count and sets `regs` to the registers used.
size_t compact_lane(const Tape& parent, const uint8_t* choices, int stride, size_t j, const uint32_t* list, size_t count,
                    Instr* end, std::vector<uint16_t>& bind_store, std::vector<uint16_t>& free_regs, uint32_t& regs) {
    constexpr uint16_t kFree = 0xFFFF;
    const size_t n = parent.code.size();
    const size_t nregs = std::max<size_t>(parent.num_regs, size_t(parent.out) + 1);
    if (bind_store.size() < nregs) bind_store.resize(nregs);
    uint16_t* bind = bind_store.data();
    std::fill_n(bind, nregs, kFree);
    const Instr* code = parent.code.data();
    const Tape::Link* links = parent.links.data();
    RegPool pool(free_regs, n + 1);
    Instr* out = end;
    bind[parent.out] = pool.alloc();
    for (size_t q = count; q-- > 0;) {
        const uint32_t i = list[q];
        const Instr& in = code[i];
        const uint16_t X = bind[in.out];
        if (X == kFree) continue;  // (cannot happen: the lane needs every listed value)
        bind[in.out] = kFree;
        const uint32_t sl = links[i].slot;
        const uint8_t ch = sl == Tape::kNone ? uint8_t(kChoiceBoth) : choices[size_t(sl) * size_t(stride) + j];
        if (ch != kChoiceBoth) {
            if (ch == kChoiceB && (in.op == Op::MinI || in.op == Op::MaxI)) {
                Instr c{Op::Const};
                c.out = X;
                c.k = in.k;
                *--out = c;
                pool.release(X);
                continue;
            }
            const uint16_t w = ch == kChoiceA ? in.a : (ch == kChoiceB ? in.b : in.c);
            if (bind[w] == kFree) {
                bind[w] = X;  // the winner's value lives in X: no instruction
            } else {
                Instr c{Op::Copy};
                c.out = X;
                c.a = bind[w];
                *--out = c;
                pool.release(X);
            }
            continue;
        }
        *--out = emit_backward(pool, in, X, [&](int op) {
            const uint16_t r = op == 0 ? in.a : (op == 1 ? in.b : in.c);
            if (bind[r] == kFree) bind[r] = pool.alloc();
            return bind[r];
        });
    }
    regs = pool.used();
    return size_t(end - out);
}

// A parent simplify cannot follow (not linked, or no output) is copied as is.
bool followable(const Tape& parent) { return parent.linked && parent.out_def != Tape::kNone; }

}  // namespace

void simplify_batch(const Tape& parent, const uint8_t* choices, int stride, uint64_t lanes, BatchScratch& s,
                    bool compact) {
    const size_t n = parent.code.size();
    s.len.fill(0);
    s.out.fill(0);
    s.cap = n;
    if (lanes == 0) return;
    const size_t blocks = size_t(64 - __builtin_clzll(lanes));  // lanes 0 .. the highest one used
    if (s.buf_size < blocks * n) {
        s.buf.reset(static_cast<Instr*>(::operator new(sizeof(Instr) * blocks * n)));
        s.buf_size = blocks * n;
    }
    Instr* buf = s.buf.get();
    if (!followable(parent)) {
        for (uint64_t m = lanes; m; m &= m - 1) {
            const int j = __builtin_ctzll(m);
            std::copy(parent.code.begin(), parent.code.end(), buf + size_t(j) * n);
            s.start[size_t(j)] = 0;
            s.len[size_t(j)] = uint32_t(n);
            s.regs[size_t(j)] = parent.num_regs;
            s.out[size_t(j)] = parent.out;
        }
        return;
    }
    need_masks(parent, choices, stride, lanes, s.mask);
    const uint64_t* need = s.mask.data();
    const Instr* code = parent.code.data();
    const Tape::Link* links = parent.links.data();
    if (!compact) {
        // Forwards: each lane's instructions in the parent's registers. A decided choice op
        // becomes a copy of the winner into its output register (nothing when the winner is
        // already there) or, for an immediate, a constant.
        std::array<uint32_t, 64> cnt{};
        for (size_t i = 0; i < n; ++i) {
            uint64_t m = need[i];
            if (!m) continue;
            const Instr in = code[i];
            const uint32_t sl = links[i].slot;
            if (sl == Tape::kNone) {
                for (; m; m &= m - 1) {
                    const size_t j = size_t(__builtin_ctzll(m));
                    buf[j * n + cnt[j]++] = in;
                }
                continue;
            }
            // What each choice byte makes of the op, and whether it takes a place: chosen
            // per lane without a branch (the lanes' choices mix unpredictably).
            Instr as[4] = {in, Instr{Op::Copy}, Instr{Op::Copy}, Instr{Op::Copy}};
            uint32_t keep[4] = {1, 1, 1, 1};
            for (int ch = kChoiceA; ch <= kChoiceC; ++ch) {
                Instr& c = as[ch];
                c.out = in.out;
                if (ch == kChoiceB && (in.op == Op::MinI || in.op == Op::MaxI)) {
                    c.op = Op::Const;
                    c.k = in.k;
                } else {
                    c.a = ch == kChoiceA ? in.a : (ch == kChoiceB ? in.b : in.c);
                    keep[ch] = c.a != c.out;  // else the winner is already in place
                }
            }
            const uint8_t* row = choices + size_t(sl) * size_t(stride);
            for (; m; m &= m - 1) {
                const size_t j = size_t(__builtin_ctzll(m));
                const uint8_t ch = row[j] & 3;
                buf[j * n + cnt[j]] = as[ch];
                cnt[j] += keep[ch];
            }
        }
        for (uint64_t lm = lanes; lm; lm &= lm - 1) {
            const size_t j = size_t(__builtin_ctzll(lm));
            s.start[j] = 0;
            s.len[j] = cnt[j];
            s.regs[j] = parent.num_regs;
            s.out[j] = parent.out;
        }
        return;
    }
    // Forwards: each lane's live instructions, as parent indices in order.
    if (s.idx_size < blocks * n) {
        s.idx.reset(new uint32_t[blocks * n]);
        s.idx_size = blocks * n;
    }
    uint32_t* idx = s.idx.get();
    std::array<uint32_t, 64> cnt{};
    for (size_t i = 0; i < n; ++i)
        for (uint64_t m = need[i]; m; m &= m - 1) {
            const size_t j = size_t(__builtin_ctzll(m));
            idx[j * n + cnt[j]++] = uint32_t(i);
        }
    for (uint64_t lm = lanes; lm; lm &= lm - 1) {
        const size_t j = size_t(__builtin_ctzll(lm));
        uint32_t regs = 1;
        const size_t nout = compact_lane(parent, choices, stride, j, idx + j * n, cnt[j], buf + j * n + n, s.bind,
                                         s.free_regs, regs);
        s.start[j] = uint32_t(n - nout);
        s.len[j] = uint32_t(nout);
        s.regs[j] = regs;
    }
}

bool fold_abs(Instr* code, size_t count, std::vector<uint32_t>& scratch) {
    // Value numbers: val[r] is the value register r holds; neg_of[v] the value v is the
    // negation of (kNoValue: none).
    constexpr uint32_t kNoValue = 0xFFFFFFFFu;
    uint32_t regs = 1;
    for (size_t i = 0; i < count; ++i) regs = std::max<uint32_t>(regs, uint32_t(std::max({code[i].out, code[i].a, code[i].b, code[i].c})) + 1);
    scratch.assign(size_t(regs) + count + 1, kNoValue);
    uint32_t* val = scratch.data();
    uint32_t* neg_of = scratch.data() + regs;
    bool changed = false;
    for (size_t i = 0; i < count; ++i) {
        Instr& in = code[i];
        const uint32_t v = uint32_t(i);
        if (in.op == Op::Copy) {
            val[in.out] = val[in.a];
            continue;
        }
        if (in.op == Op::Neg && val[in.a] != kNoValue) {
            const uint32_t a = val[in.a];
            if (neg_of[a] != kNoValue) {  // -(-x): x itself
                val[in.out] = neg_of[a];
                continue;
            }
            neg_of[v] = a;
        } else if (in.op == Op::Max && val[in.a] != kNoValue && val[in.b] != kNoValue) {
            const uint32_t a = val[in.a], b = val[in.b];
            if (neg_of[a] == b || neg_of[b] == a) {
                in.op = Op::Abs;
                in.b = 0;
                changed = true;
            }
        }
        val[in.out] = v;
    }
    return changed;
}

void simplify_masks(const Tape& parent, const uint8_t* choices, int stride, uint64_t lanes, BatchScratch& s) {
    if (lanes != 0 && followable(parent)) need_masks(parent, choices, stride, lanes, s.mask);
}

}  // namespace sdfc
