// Building the tape tree (tape_tree.hpp). Best first: the cells worth splitting wait in a
// queue ordered by tape length x size^2 (roughly the evaluations a split saves: long tapes,
// big surfaces), and rounds of up to kTreeRound of them are split in parallel until the
// queue empties or the work budget (instructions interval-evaluated) runs out.
// Deterministic for any thread count.
// `lipschitz`: the program is a 1-Lipschitz distance bound, so a child's interval can be
// tightened with the value at its centre c: d(p) is within |p - c| of d(c). That rescues
// fields whose intervals are weak far away (rotations by an angle that depends on the
// point: twist, bend). The tightened bounds decide splits and rays' jumps (as safe as a
// sphere-tracing step); tape simplification uses the interval choices alone.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")  // as in marcher.cpp
#endif
#include "runtime/cpu/tape_tree.hpp"

#include "compiler/render/rules.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <deque>
#include <memory>
#include <queue>

#include "runtime/eval/interval.hpp"
#include "runtime/eval/vm.hpp"

namespace sdfc::cpu {
namespace {

constexpr int kTreeMaxDepth = 16;
constexpr size_t kTreeLeafTape = 64;      // tapes this short are not split further ...
// ... unless the field is raw (no distance bound): its marches step a pixel at a time near
// the surface, and every empty cell a split finds there is a jump over many steps
// (colonnade.vm at 1024^2: 59.8 -> 25.4 evaluations a pixel; with the jumps of all lanes
// together in Worker::run, 0.73x the time).
constexpr size_t kTreeRawLeafTape = 0;
constexpr size_t kTreePilot = 32;          // after splits worth this many programs ...
constexpr double kTreeUseless = 0.6;      // ... surface cells' tapes this long: no tree
constexpr size_t kTreeMaxNodes = size_t(1) << 20;
// ... and at most one node per kTreeSamplesPerNode samples of the picture (at least
// kTreeMinNodes): past that, leaves are so small that a window's lanes fall into many of
// them and the distance batches run nearly empty (the 10,000-sphere grid at 640 x 360:
// 50,709 leaves, 3.5 points a batch; capped at 14,400 nodes it took 0.92x the time,
// recursive1.sdf 0.90x, vases.sdf 0.94x, showcase.sdf 1.01x).
constexpr size_t kTreeSamplesPerNode = 16, kTreeMinNodes = 4096;
// Under a thin layer (its root centred below it, frame.cpp settle_thin_layer) the surface
// cells are half as many a level, so the same budget would take its leaves a level deeper,
// into batches too small to fill: one node per 24 samples. Against 16 (and the root centred
// as before), 2 threads, 5 rounds alternating: the 10,000-sphere grid 0.79x at 640 x 360,
// 0.86x at 1280 x 720; 1,024 spheres 0.98x; 3,600 spheres (test_accel) 0.95x at 160 x 90,
// 0.93x at 640 x 360, but 1.08x at 1280 x 720, where the budget does not bind and the
// taller root's cells give 23,004 leaves instead of 17,880.
constexpr size_t kTreeThinSamplesPerNode = 24;
constexpr int kTreeMaxStall = 3;          // splits in a row that did not shorten tapes (x 0.9)
constexpr float kTreeNear = 0.25f;        // empty cells are split when the surface is this near (x size) ...
// ... but not under a thin layer: there the settled cells near the surface are the air just
// above (or the ground just below) the layer, whose tapes keep nearly every object within
// reach, so their splits spend the node budget for little (the 10,000-sphere grid at
// 640 x 360, 2 threads: 0.93x the time, 1,024 spheres 0.95x; not for the examples, which
// have no thin layer: showcase.sdf takes 1.17x without them, vases.sdf 1.04x).
constexpr float kTreeThinNear = 0.0f;
constexpr size_t kTreeRound = 64;         // cells split in parallel per round
// Build work budget (instructions interval-evaluated, 8 boxes at a time): a constant, plus
// per program instruction, plus per sample of the image (the evaluations it will save).
constexpr size_t kTreeWorkPerInstr = 64, kTreeWorkBase = size_t(16) << 10, kTreeWorkPerSample = 1;
// The tapes a build makes (instructions, kept or not) are bounded too. Copying them into
// fresh memory is the cost where tapes barely shrink (a smooth_union of 15,000 spheres:
// children 0.6-0.8 of their parent's length): uncapped, its build made 757 leaves of
// 94,000 instructions, 1.1 GB, and took 4.9 s of a 7.2 s render at 64 x 48; capped, 50
// leaves, 0.5 s of 1.9 s. The examples make at most 2.7 M (vases.sdf), the 10,000-sphere
// grid 0.8 M: the cap leaves them as they were. A round reserves what its children may
// make: 8 x their parent's length, times the share kept by the children made so far.
constexpr size_t kTreeMadeBase = size_t(8) << 20, kTreeMadePerInstr = 32;
constexpr uint32_t kNone = 0xFFFFFFFFu;

struct TreeCell {
    glm::vec3 lo{0}, hi{0};
    float ivlo = -INFINITY, ivhi = INFINITY;
    int depth = 0, stall = 0;
    // An empty (or solid) cell that will not be split runs its parent's tape (valid in the
    // parent's box, hence in its own): ref_cell is the parent.
    uint32_t ref_cell = kNone;
    // Split axes (bit a: axis a halved). A cell is split only along axes at least half as
    // long as its longest, so cells stay roughly cubic: a flat scene's thin layer is not
    // cut into slabs that each cost a full split. Children on the upper side of an unsplit
    // axis are `unused`: descents never reach them (their split coordinate is +inf).
    uint8_t axes = 7;
    bool unused = false;
    Tape tape;
};

// The axes a cell is split along: those at least half as long as its longest.
uint8_t split_axes(const TreeCell& c) {
    const glm::vec3 e = c.hi - c.lo;
    const float m = rules::sdf_max3(e);
    uint8_t axes = 0;
    for (int a = 0; a < 3; ++a) axes |= uint8_t(e[a] >= 0.5f * m) << a;
    return axes ? axes : uint8_t(7);  // (NaN extents: all, as before)
}

// Empty (ivlo > 0) or solid (ivhi < 0): no surface inside.
bool settled(float ivlo, float ivhi) { return ivlo > 0.0f || ivhi < 0.0f; }
// An empty or solid cell is still split when the surface is within `near` (kTreeNear) of its
// size (rays, normal and AO taps and soft shadows evaluate there).
bool near_surface(const TreeCell& c, float near) {
    const float size = rules::sdf_max3(c.hi - c.lo), d = c.ivlo > 0.0f ? c.ivlo : -c.ivhi;
    if (c.ivlo == kSheet) return false;  // (no surface near: at most a sheet)
    return d < near * size;
}

bool want_split(const TreeCell& c, size_t leaf_tape, float near) {
    if (c.ref_cell != kNone || c.unused) return false;
    if (c.depth >= kTreeMaxDepth || c.tape.code.size() <= leaf_tape || c.stall >= kTreeMaxStall) return false;
    const float size = rules::sdf_max3(c.hi - c.lo);
    if (!(size > 0.0f) || !std::isfinite(size)) return false;
    return !settled(c.ivlo, c.ivhi) || near_surface(c, near);  // may hold the surface, or unknown (NaN)
}

// Per-thread evaluators of the build, grown to the largest tape seen.
struct TreeScratch {
    std::unique_ptr<IntervalEvaluator> iv;
    uint32_t regs = 0, choices = 0;
    BatchScratch bs;
    std::vector<Tape::Link> links;  // lent to the cell being split
    std::vector<uint32_t> fold;  // fold_abs's
    uint64_t boxes = 0;
    std::unique_ptr<BatchVM> vm;  // grows to the longest tape it runs
    IntervalEvaluator& get(uint32_t r, uint32_t c) {
        if (!iv || r > regs || c > choices) {
            regs = std::max(regs, r);
            choices = std::max(choices, c);
            iv = std::make_unique<IntervalEvaluator>(regs, choices);
            iv->keep_chains(true);
        }
        return *iv;
    }
    BatchVM& point_vm() {
        if (!vm) vm = std::make_unique<BatchVM>(64);
        return *vm;
    }
};

// The cells of one build (cell i becomes node i), the queue of cells worth splitting and
// the work spent against the budget.
class TreeBuilder {
public:
    TreeBuilder(const Program& p, glm::vec3 lo, glm::vec3 hi, float time, bool lipschitz, size_t samples, bool thin_layer)
        : p_(p), time_(time), lipschitz_(lipschitz), near_(thin_layer ? kTreeThinNear : kTreeNear),
          budget_(kTreeWorkBase + kTreeWorkPerInstr * p.code.size() + kTreeWorkPerSample * samples),
          made_cap_(std::max(kTreeMadeBase, kTreeMadePerInstr * p.code.size())),
          max_nodes_(std::clamp(samples / (thin_layer ? kTreeThinSamplesPerNode : kTreeSamplesPerNode), kTreeMinNodes, kTreeMaxNodes)) {
        cells_[0].lo = lo, cells_[0].hi = hi;
        cells_[0].tape = Tape::from(p, 0);
        std::vector<uint32_t> fold;
        if (fold_abs(cells_[0].tape.code.data(), cells_[0].tape.code.size(), fold)) cells_[0].tape.link();
        cells_[0].tape.mark_min_chains();  // a union's far shapes go against its nearest anywhere
        consider(0);
    }

    bool queued() const { return !queue_.empty(); }

    // Once the tree is a few levels deep (checked once): if the tapes of the cells that may
    // hold the surface are not much shorter than the program (smooth blends, domain
    // repetition: nothing for the intervals to decide), the lookups would cost more than
    // they save. True when that is the case.
    bool pilot_rejects() {
        if (checked_ || work_ < kTreePilot * p_.code.size()) return false;
        checked_ = true;
        size_t n = 0, len = 0;
        for (size_t i = 0; i < cells_.size(); ++i)
            if (first_child_[i] == kNone && cells_[i].ref_cell == kNone && !cells_[i].unused && !settled(cells_[i].ivlo, cells_[i].ivhi))
                ++n, len += cells_[i].tape.code.size();
        return n > 0 && static_cast<double>(len) > kTreeUseless * static_cast<double>(n) * static_cast<double>(p_.code.size());
    }

    // Takes the next round off the queue, best first, while the budget and the node limit
    // allow; false when not even one cell fits.
    bool take_round() {
        round_.clear();
        size_t reserved = 0;
        while (!queue_.empty() && round_.size() < kTreeRound && cells_.size() + 8 * (round_.size() + 1) <= max_nodes_) {
            const uint32_t i = ~queue_.top().second;
            const size_t len = cells_[i].tape.code.size();
            // (what the children's tapes may take, before they are known: 8 x len times the
            // share of their parents' length the children made so far have kept)
            const double keep = split_ ? std::clamp(double(made_) / (8.0 * double(split_)), 0.125, 1.0) : 1.0;
            const size_t expect = size_t(8.0 * double(len) * keep);
            if (work_ + len > budget_ || made_ + reserved + expect > made_cap_) break;
            reserved += expect;
            queue_.pop();
            work_ += len;
            round_len_ += len;
            round_.push_back(i);
        }
        return !round_.empty();
    }

    // Splits the round's cells in parallel, then queues those of their children worth
    // splitting (in cell order, so the queue is the same for any thread count).
    void split_round() {
        const uint32_t base = static_cast<uint32_t>(cells_.size());
        cells_.resize(cells_.size() + 8 * round_.size());
        first_child_.resize(cells_.size(), kNone);
        keep_.resize(cells_.size(), 0);
        for (size_t q = 0; q < round_.size(); ++q) first_child_[round_[q]] = base + static_cast<uint32_t>(8 * q);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, round_.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
            TreeScratch& s = scratch_.local();
            for (size_t q = r.begin(); q != r.end(); ++q) split(s, round_[q]);
        });
        split_ += round_len_;
        round_len_ = 0;
        for (size_t q = 0; q < round_.size(); ++q)
            for (uint32_t k = 0; k < 8; ++k) {
                made_ += cells_[first_child_[round_[q]] + k].tape.code.size();
                consider(first_child_[round_[q]] + k);
            }
    }

    bool any_split() const { return cells_.size() > 1; }
    uint64_t boxes() const {
        uint64_t n = 0;
        for (const TreeScratch& s : scratch_) n += s.boxes;
        return n;
    }
    // Nodes, leaves and tapes into T, in cell order (deterministic; parents precede children).
    void emit(TapeTree& T);

private:
    void consider(uint32_t i) {
        const TreeCell& c = cells_[i];
        if (!want_split(c, lipschitz_ ? kTreeLeafTape : kTreeRawLeafTape, near_)) return;
        const double size = rules::sdf_max3(c.hi - c.lo);
        const double prio = static_cast<double>(c.tape.code.size()) * size * size * (settled(c.ivlo, c.ivhi) ? 0.25 : 1.0);
        queue_.emplace(prio, ~i);
    }
    void split(TreeScratch& s, uint32_t i);
    void make_ropes(TapeTree& T) const;

    const Program& p_;
    const float time_;
    const bool lipschitz_;
    const float near_;  // kTreeNear, or kTreeThinNear under a thin layer
    const size_t budget_;
    const size_t made_cap_;
    const size_t max_nodes_;
    size_t work_ = 0;
    size_t made_ = 0;   // instructions of the tapes made, against made_cap_
    size_t split_ = 0;  // ... and of their parents'
    size_t round_len_ = 0;  // (the parents' of the round taken)
    bool checked_ = false;
    std::deque<TreeCell> cells_ = std::deque<TreeCell>(1);  // a deque: growing moves nothing
    std::vector<uint32_t> first_child_ = std::vector<uint32_t>(1, kNone);
    std::vector<uint8_t> keep_ = std::vector<uint8_t>(1, 0);  // the cell's tape is run by settled children
    using Item = std::pair<double, uint32_t>;  // (priority, ~index): ties go to the lower index
    std::priority_queue<Item> queue_;
    std::vector<uint32_t> round_;
    tbb::enumerable_thread_specific<TreeScratch> scratch_;
};

// Cell i's 8 children: their boxes, intervals (tightened by centre values where the
// intervals alone leave them ambiguous), and simplified tapes, or a reference to this
// cell's tape for those that will not be split.
void TreeBuilder::split(TreeScratch& s, uint32_t i) {
    TreeCell& c = cells_[i];
    const uint32_t first = first_child_[i];
    const glm::vec3 mid = 0.5f * (c.lo + c.hi);
    c.axes = split_axes(c);
    float bx[6][kIvLanes];
    for (int k = 0; k < 8; ++k)
        for (int a = 0; a < 3; ++a) {
            const bool split = (c.axes >> a) & 1, upper = (k >> a) & 1;
            bx[2 * a][k] = !split ? c.lo[a] : (upper ? mid[a] : c.lo[a]);
            bx[2 * a + 1][k] = !split ? c.hi[a] : (upper ? c.hi[a] : mid[a]);
        }
    if (!c.tape.linked) {
        c.tape.links.swap(s.links);  // the thread's links array, grown once (see the end)
        c.tape.link();
    }
    IntervalEvaluator& iv = s.get(c.tape.num_regs, c.tape.choices);
    iv.eval(c.tape, bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], 8, time_);
    iv.prune_min_chains(c.tape, 8);
    s.boxes += 8;
    // Children the intervals leave ambiguous: tighten with the centre values (one
    // evaluation of this cell's tape at the 8 centres).
    bool ambiguous = false;
    for (int k = 0; k < 8; ++k) ambiguous |= !settled(iv.result(k).lo, iv.result(k).hi);
    float dc[8];
    std::fill_n(dc, 8, NAN);
    if (lipschitz_ && ambiguous) {
        alignas(64) float cx[kBatch], cy[kBatch], cz[kBatch];
        for (int k = 0; k < 8; ++k) {
            cx[k] = 0.5f * (bx[0][k] + bx[1][k]);
            cy[k] = 0.5f * (bx[2][k] + bx[3][k]);
            cz[k] = 0.5f * (bx[4][k] + bx[5][k]);
        }
        BatchVM& vm = s.point_vm();
        const TapeView tape = c.tape.view();
        vm.eval(tape, cx, cy, cz, 8, time_);
        std::copy_n(vm.output(tape), 8, dc);
    }
    bool kept = false;
    uint64_t lanes = 0;
    size_t sheets = 0;  // children settled as sheets: surface cells whose tapes the split ended
    for (int k = 0; k < 8; ++k) {
        TreeCell& ch = cells_[first + static_cast<uint32_t>(k)];
        ch.lo = glm::vec3(bx[0][k], bx[2][k], bx[4][k]);
        ch.hi = glm::vec3(bx[1][k], bx[3][k], bx[5][k]);
        const Interval v = iv.result(k);
        const Interval t = std::isfinite(dc[k]) ? tighten_by_centre(v, dc[k], glm::length(ch.hi - ch.lo)) : v;
        ch.ivlo = t.lo, ch.ivhi = t.hi;
        if (!lipschitz_) ch.ivlo = raw_floor(ch.ivlo, ch.ivhi);
        ch.depth = c.depth + 1;
        ch.unused = (k & ~c.axes) != 0;
        if (ch.unused) continue;  // (a copy of a used sibling's box)
        if (settled(ch.ivlo, ch.ivhi) && !(ch.depth < kTreeMaxDepth && c.tape.code.size() > kTreeLeafTape && near_surface(ch, near_))) {
            ch.ref_cell = i;  // will not be split: runs this cell's tape
            kept = true;
            sheets += ch.ivlo == kSheet;
            continue;
        }
        lanes |= uint64_t(1) << k;
    }
    size_t sum = 0, nsimp = 0;
    if (lanes) simplify_batch(c.tape, iv.choices(), iv.stride(), lanes, s.bs, true);
    for (int k = 0; k < 8; ++k) {
        if (!((lanes >> k) & 1)) continue;
        TreeCell& ch = cells_[first + static_cast<uint32_t>(k)];
        ch.tape.assign(s.bs.code(k), s.bs.len[size_t(k)], s.bs.out[size_t(k)], s.bs.regs[size_t(k)]);
        if (fold_abs(ch.tape.code.data(), ch.tape.code.size(), s.fold) && !lipschitz_ && !settled(ch.ivlo, ch.ivhi)) {
            // A sheet of zero thickness may be all the surface the box has: its own
            // interval, which knows abs(x) is not negative, says.
            const float blo[3] = {ch.lo.x, ch.lo.y, ch.lo.z}, bhi[3] = {ch.hi.x, ch.hi.y, ch.hi.z};
            iv.eval(ch.tape.view(), &blo[0], &bhi[0], &blo[1], &bhi[1], &blo[2], &bhi[2], 1, time_);
            const Interval r = iv.result(0);
            if (r.lo > ch.ivlo) ch.ivlo = r.lo;
            if (r.hi < ch.ivhi) ch.ivhi = r.hi;
            ch.ivlo = raw_floor(ch.ivlo, ch.ivhi);
        }
        sum += ch.tape.code.size();
        ++nsimp;
    }
    // A split that left the children's tapes about as long as this one (an
    // unprunable field) counts against splitting them again. (Sheets count as tapes of no
    // length: without the proof they were short surface tapes.)
    nsimp += sheets;
    const bool useless = nsimp > 0 && sum * 10 >= c.tape.code.size() * nsimp * 9;
    for (int k = 0; k < 8; ++k) cells_[first + static_cast<uint32_t>(k)].stall = useless ? c.stall + 1 : 0;
    keep_[i] = kept;
    // The links are not needed again: back to the thread (a fresh array per split cost a
    // page fault every 256 instructions, about 5 us each on this VM).
    s.links.swap(c.tape.links);
    c.tape.links.clear();
    c.tape.linked = false;
    if (!kept) c.tape = Tape{};  // no longer needed: free it now
}

void TreeBuilder::emit(TapeTree& T) {
    T.nodes.resize(cells_.size());
    T.boxes_.resize(cells_.size());
    // The tapes of split cells that settled children run: (code, len, out) by cell.
    struct Kept {
        const Instr* code = nullptr;
        uint32_t len = 0;
        uint16_t out = 0;
    };
    std::vector<Kept> kept;
    std::vector<uint32_t> kept_of(cells_.size(), kNone);
    T.tapes.reserve(cells_.size() + 1);  // (moves only: the leaves' code pointers stay valid)
    for (size_t i = 0; i < cells_.size(); ++i) {
        TreeCell& c = cells_[i];
        TapeTree::Node& node = T.nodes[i];
        for (int a = 0; a < 3; ++a) T.boxes_[i].lo[a] = c.lo[a], T.boxes_[i].hi[a] = c.hi[a];
        if (c.unused) {  // never reached; points at leaf 0 (the full program) all the same
            node.child = TapeTree::kLeafBit;
            for (int a = 0; a < 3; ++a) T.boxes_[i].lo[a] = INFINITY, T.boxes_[i].hi[a] = -INFINITY;
            continue;
        }
        if (first_child_[i] != kNone) {
            const glm::vec3 mid = 0.5f * (c.lo + c.hi);
            for (int a = 0; a < 3; ++a) node.c[a] = (c.axes >> a) & 1 ? mid[a] : INFINITY;
            node.child = first_child_[i];
            for (uint32_t k = 0; k < 8; ++k) T.boxes_[first_child_[i] + k].parent = static_cast<uint32_t>(i);
            if (keep_[i]) {
                kept_of[i] = static_cast<uint32_t>(kept.size());
                kept.push_back(Kept{nullptr, static_cast<uint32_t>(c.tape.code.size()), c.tape.out});
                T.tapes.push_back(std::move(c.tape.code));
                kept.back().code = T.tapes.back().data();
                T.max_regs = std::max(T.max_regs, c.tape.num_regs);
            }
            continue;
        }
        TapeTree::Leaf L{};
        for (int a = 0; a < 3; ++a) L.lo[a] = c.lo[a], L.hi[a] = c.hi[a];
        L.ivlo = c.ivlo, L.ivhi = c.ivhi;
        L.node = static_cast<uint32_t>(i);
        if (c.ref_cell != kNone) {
            const Kept& k = kept[kept_of[c.ref_cell]];
            L.code = k.code, L.len = k.len, L.out = k.out;
        } else {
            L.len = static_cast<uint32_t>(c.tape.code.size());
            L.out = c.tape.out;
            T.tapes.push_back(std::move(c.tape.code));
            L.code = T.tapes.back().data();
            T.max_regs = std::max(T.max_regs, c.tape.num_regs);
        }
        node.child = TapeTree::kLeafBit | static_cast<uint32_t>(T.leaves.size());
        T.leaves.push_back(L);
    }
    make_ropes(T);
    // Bottom up (children follow parents): which nodes hold only empty leaves, and their
    // least lower bound (unused children are never reached, so count as empty).
    for (size_t i = cells_.size(); i-- > 0;) {
        const TapeTree::Node& node = T.nodes[i];
        float e = INFINITY;
        if (node.child & TapeTree::kLeafBit) {
            if (!cells_[i].unused) e = T.leaves[node.child & ~TapeTree::kLeafBit].ivlo;
        } else {
            for (uint32_t k = 0; k < 8; ++k) e = std::min(e, T.boxes_[node.child + k].elo);  // (-inf wins)
        }
        T.boxes_[i].elo = e > 0.0f ? e : -INFINITY;  // (NaN: not empty)
    }
    // Top down: each node's biggest empty ancestor (itself if its parent is not empty).
    std::vector<uint32_t> up(cells_.size());
    for (size_t i = 0; i < cells_.size(); ++i) {
        const uint32_t p = T.boxes_[i].parent;
        up[i] = i != 0 && T.boxes_[p].empty() ? up[p] : static_cast<uint32_t>(i);
    }
    for (size_t l = 1; l < T.leaves.size(); ++l) {
        TapeTree::Leaf& L = T.leaves[l];
        L.up = L.ivlo > 0.0f ? up[L.node] : L.node;
    }
}

// Top down (parents precede children): a child's neighbour across a face inside its parent
// is its sibling; across one of the parent's faces, it is the parent's neighbour, or that
// neighbour's child facing it when the neighbour is as small as the parent and split (cells
// of one depth have the same extents, hence the same split axes, and share face
// coordinates bit for bit: both come from their common ancestor's split).
void TreeBuilder::make_ropes(TapeTree& T) const {
    constexpr int R = TapeTree::kRopeRow;
    std::vector<uint32_t> ropes(cells_.size() * R, 0);  // by node
    for (size_t i = 0; i < cells_.size(); ++i) {
        const uint32_t first = first_child_[i];
        if (first == kNone) continue;
        const TreeCell& c = cells_[i];
        for (uint32_t k = 0; k < 8; ++k) {
            const uint32_t ch = first + k;
            uint32_t* row = &ropes[size_t(ch) * R];
            row[6] = ch;
            if (cells_[ch].unused) continue;
            for (int f = 0; f < 6; ++f) {
                const int a = f >> 1;
                const uint32_t bit = 1u << a;
                const bool split = (c.axes >> a) & 1, upper = (k & bit) != 0, plus = f & 1;
                if (split && upper != plus) {  // the sibling on the other side of the midplane
                    row[f] = first + (k ^ bit);
                    continue;
                }
                uint32_t m = ropes[i * R + size_t(f)];
                if (m != 0 && cells_[m].depth == c.depth && first_child_[m] != kNone)
                    m = first_child_[m] + (split ? (k ^ bit) : k);  // its child facing this one
                row[f] = m;
            }
        }
    }
    T.ropes.assign(T.leaves.size() * R, 0);  // by leaf (leaf 0: the root's row, all 0)
    for (size_t l = 1; l < T.leaves.size(); ++l)
        std::copy_n(&ropes[size_t(T.leaves[l].node) * R], R, &T.ropes[l * R]);
}

}  // namespace

bool TapeTree::all_empty(const glm::vec3& blo, const glm::vec3& bhi) const {
    if (!active) return false;
    for (int a = 0; a < 3; ++a)
        if (!(blo[a] >= boxes_[0].lo[a] && bhi[a] <= boxes_[0].hi[a])) return false;  // (NaN: false)
    if (boxes_[0].empty()) return true;
    uint32_t stack[8 * (kTreeMaxDepth + 1)];  // depth first: at most 8 a level
    int sp = 0, visits = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const Node& N = nodes[stack[--sp]];
        if (++visits > kEmptyVisits) return false;
        for (uint32_t k = 0; k < 8; ++k) {
            const uint32_t c = N.child + k;
            const NodeBox& B = boxes_[c];
            const bool meets = B.lo[0] <= bhi.x && B.hi[0] >= blo.x && B.lo[1] <= bhi.y && B.hi[1] >= blo.y && B.lo[2] <= bhi.z &&
                               B.hi[2] >= blo.z;
            if (!meets || B.empty()) continue;
            if (nodes[c].child & kLeafBit) return false;  // a leaf that may hold surface
            stack[sp++] = c;
        }
    }
    return true;
}

void build_tree(TapeTree& T, const Program& p, glm::vec3 lo, glm::vec3 hi, float time, bool lipschitz, size_t samples,
                bool thin_layer) {
    T.init_full(p);
    T.lo = lo;
    T.hi = hi;
    T.time = time;
    T.active = true;
    TreeBuilder b(p, lo, hi, time, lipschitz, samples, thin_layer);
    bool worth_it = true;
    while (b.queued()) {
        if (b.pilot_rejects()) {
            worth_it = false;
            break;
        }
        if (!b.take_round()) break;
        b.split_round();
    }
    T.boxes += b.boxes();
    if (!worth_it || !b.any_split()) return T.init_full(p);  // no tree: leaf 0 only
    b.emit(T);
}

}  // namespace sdfc::cpu
