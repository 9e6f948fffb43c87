// The kept tape tree (tree_cache.hpp).
#include "runtime/cpu/tree_cache.hpp"

#include <algorithm>
#include <cstring>
#include <mutex>

namespace sdfc::cpu {
namespace {

struct Kept {
    TreeInputs in;
    bool reads_time = false;
    uint32_t num_regs = 0;
    uint16_t out = 0;
    std::vector<Guard> guards;
    std::shared_ptr<const TapeTree> tree;  // its tapes[0] is the program's code
};

std::mutex kept_mutex;
Kept kept;

bool reads_time(const Program& p) {
    return std::any_of(p.code.begin(), p.code.end(), [](const Instr& in) { return in.op == Op::Time; });
}

bool same_bits(const void* a, const void* b, size_t bytes) { return bytes == 0 || std::memcmp(a, b, bytes) == 0; }

// (field by field: an Instr has padding bytes, which memcmp would read)
bool same_code(const std::vector<Instr>& a, const std::vector<Instr>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i) {
        const Instr &x = a[i], &y = b[i];
        if (x.op != y.op || x.pad != y.pad || x.out != y.out || x.a != y.a || x.b != y.b || x.c != y.c || !same_bits(&x.k, &y.k, sizeof x.k))
            return false;
    }
    return true;
}

bool same_guards(const std::vector<Guard>& a, const std::vector<Guard>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
        if (!same_bits(a[i].lo, b[i].lo, sizeof a[i].lo) || !same_bits(a[i].hi, b[i].hi, sizeof a[i].hi) || a[i].px != b[i].px ||
            a[i].py != b[i].py || a[i].pz != b[i].pz || a[i].end != b[i].end)
            return false;
    return true;
}

// Whether the kept tree was built from `p` and `in` (floats compared bit for bit).
bool matches(const Kept& k, const Program& p, const TreeInputs& in, bool time) {
    if (!k.tree || p.outputs.empty() || k.out != p.outputs[0] || k.num_regs != p.num_regs || k.reads_time != time) return false;
    if (!same_bits(&k.in.lo, &in.lo, sizeof in.lo) || !same_bits(&k.in.hi, &in.hi, sizeof in.hi)) return false;
    if (time && !same_bits(&k.in.time, &in.time, sizeof in.time)) return false;
    if (k.in.lipschitz != in.lipschitz || k.in.samples != in.samples || k.in.thin_layer != in.thin_layer) return false;
    return same_code(k.tree->tapes[0], p.code) && same_guards(k.guards, p.guards);
}

}  // namespace

std::shared_ptr<const TapeTree> shared_tree(const Program& p, const TreeInputs& in, bool keep, bool* reused) {
    const bool time = reads_time(p);
    if (reused) *reused = false;
    if (keep) {
        std::lock_guard<std::mutex> l(kept_mutex);
        if (matches(kept, p, in, time)) {
            if (reused) *reused = true;
            return kept.tree;
        }
    }
    auto tree = std::make_shared<TapeTree>();
    build_tree(*tree, p, in.lo, in.hi, in.time, in.lipschitz, in.samples, in.thin_layer);
    if (keep) {
        Kept k{in, time, p.num_regs, p.outputs.empty() ? uint16_t(0) : p.outputs[0], p.guards, tree};
        std::shared_ptr<const TapeTree> old;
        {
            std::lock_guard<std::mutex> l(kept_mutex);
            old = std::move(kept.tree);  // (freed outside the lock)
            kept = std::move(k);
        }
    }
    return tree;
}

void forget_tree() {
    std::shared_ptr<const TapeTree> old;
    std::lock_guard<std::mutex> l(kept_mutex);
    old = std::move(kept.tree);
    kept = Kept{};
}

}  // namespace sdfc::cpu
