// The Prospero image of a 2D field (render_2d, declared in runtime/cpu/slice.hpp): a quadtree
// over the image with interval arithmetic and per-tile tape simplification.
//
//   whole image (N = power of two >= w, h) -> 4 x 4 tiles of N/4 -> ... while tiles are
//   >= 128 pixels, then 8 x 8 leaves of 8 x 8 pixels (1024 -> 256 -> 64 -> 8).
//   Each level evaluates all children of a tile at once (one interval lane per child, see
//   runtime/eval/interval.hpp) with the tile's tape. A child whose interval is < 0 is filled
//   white; one >= 0 stays black (the image starts black); the others get their own shorter
//   tape (simplify_batch: all children of a tile in one pass) and are subdivided. Only the
//   sign of the output matters, so min/max ops are also decided by sign (kSignOnly in
//   runtime/eval/tape.hpp): a shape positive over a tile leaves a union there even where
//   its interval overlaps a straddling shape's. The leaves of a tile run in one sweep
//   (SweepVM, runtime/eval/vm.hpp): the tile's tape walked once, each instruction run for
//   every leaf that needs it (simplify_masks) as that leaf's trace would run it, so no
//   leaf tape is made, and one leaf's op does not wait for the one before it. The tiles
//   just above the leaves get traces (the parent's live instructions), the levels above
//   compacted tapes.
//   The top levels run their children as oneTBB tasks while their tiles are few for the
//   threads (Ctx::nested: one level for 2 threads), each task with scratch from a pool
//   (not per thread: a thread waiting in a nested parallel_for may run another task). Each
//   such task simplifies its own tape (simplify: about the result's length of work), so the
//   top tile's serial part is its interval pass alone.
//
// Exactness: the interval bounds enclose the VM's float results bit for bit, and a
// simplified tape computes, inside its tile, floats with the same sign (< 0 or not) as its
// parent's, so the image is identical to brute-force evaluation (tests/runtime/test_raster2d.cpp, pixel by pixel).
#include <algorithm>
#include <atomic>
#include <cstring>
#include <memory>
#include <mutex>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include "compiler/render/rules.h"
#include "runtime/eval/interval.hpp"
#include "runtime/cpu/slice.hpp"
#include "runtime/eval/vm.hpp"

// GCC cannot see that the evaluators read only the first n lanes of their inputs.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace sdfc {
namespace {

// Pixel coordinates, shared by every path so they produce the same floats. Both are
// monotonic in the pixel index, so a tile's coordinate interval is its corner pixels'.
inline float coord_x(int i, int w) { return rules::sdf_grid_x(i, w); }  // (compiler/render/rules.h: the
inline float coord_y(int j, int h) { return rules::sdf_grid_y(j, h); }  // shader samples the same grid)

constexpr int kLeaf = 8;       // leaf tiles: 8 x 8 pixels = one VM batch
constexpr int kMaxDepth = 12;  // 2^12 * 8 pixels: far beyond any image size we accept
static_assert(kLeaf * kLeaf == kBatch);

struct Scratch {
    Scratch(const Program& prog, const Tape& root) : ev(prog.num_regs), root_regs(root.num_regs), root_choices(root.choices) {
        iv.resize(kMaxDepth);
        tapes.resize(kMaxDepth + 1);
        batch.resize(kMaxDepth);
    }
    IntervalEvaluator& interval(int depth) {
        auto& p = iv[size_t(depth)];
        if (!p) p = std::make_unique<IntervalEvaluator>(root_regs, root_choices);
        return *p;
    }
    BatchVM ev;  // every tape of the quadtree, sized by the root's registers
    SweepVM sweep;                                       // the leaves of a tile, all at once
    std::vector<float> edge;                             // inputs of leaves cut by the image's edge
    uint32_t root_regs, root_choices;
    std::vector<std::unique_ptr<IntervalEvaluator>> iv;  // per depth: the choices stay readable while children run
    std::vector<Tape> tapes;                             // per depth: the tape of the tile being processed
    std::vector<BatchScratch> batch;                     // per depth: the children's tapes (or masks)
    SimplifyScratch lane;                                // simplify() of a task's own tile
    uint64_t points = 0;                                 // evaluated at the leaves, since acquired
};

// Scratch objects handed to tasks (not threads: a thread waiting in a nested parallel_for
// may run another task, which must not share its scratch).
class Pool {
public:
    Pool(const Program& p, const Tape& root) : prog_(p), root_(root) {}
    Scratch* acquire() {
        {
            std::lock_guard<std::mutex> l(m_);
            if (!free_.empty()) {
                Scratch* s = free_.back();
                free_.pop_back();
                return s;
            }
        }
        auto s = std::make_unique<Scratch>(prog_, root_);
        std::lock_guard<std::mutex> l(m_);
        all_.push_back(std::move(s));
        return all_.back().get();
    }
    void release(Scratch* s) {
        std::lock_guard<std::mutex> l(m_);
        free_.push_back(s);
    }

private:
    const Program& prog_;
    const Tape& root_;
    std::mutex m_;
    std::vector<std::unique_ptr<Scratch>> all_;
    std::vector<Scratch*> free_;
};

struct Ctx {
    int w, h;
    float* px;  // w * h, one channel
    float time;
    Pool* pool;
    std::vector<float> xc, yc;  // coord_x / coord_y of every column / row
    // The x and y inputs of every full 8 x 8 leaf batch, by column block and row block
    // (block_inputs): a leaf hands the VM these rows instead of writing its own just before,
    // whose narrower stores the VM's wide loads then waited for (store forwarding fails).
    std::vector<float> xb, yb;
    std::vector<int> sizes;  // tile size per depth: sizes[0] the root, the last the leaves
    int threads = 1;
    std::atomic<uint64_t> points{0};  // the scratch objects' counts, as they go back to the pool
    // Whether the children of a tile at `depth` run as tasks: while the tiles of that depth
    // are fewer than 4 per thread. Deeper levels then run in their parent's task, with its
    // scratch still in cache (measured at 2 threads: ~6 % faster than tasks at every level
    // of tiles >= 64 pixels, which many threads still get).
    bool nested(int depth) const {
        const size_t per_axis = size_t(sizes[0] / sizes[size_t(depth)]);
        return per_axis * per_axis < 4 * size_t(threads);
    }
};

void fill(Ctx& c, int x0, int y0, int x1, int y1, float v) {
    for (int y = y0; y < y1; ++y) std::fill(c.px + size_t(y) * c.w + x0, c.px + size_t(y) * c.w + x1, v);
}

// The pixels of a 8 x 8 leaf from the VM's results (d: row r at d + r * cols).
void write_leaf(Ctx& c, Scratch& s, const float* d, int bx, int by) {
    const int x1 = std::min(bx + 8, c.w), y1 = std::min(by + 8, c.h);
    const int cols = x1 - bx, rows = y1 - by, n = cols * rows;
    // Into a local row first: the compiler cannot tell the picture from the VM's
    // registers, and would write pixel by pixel.
    alignas(64) float in[kBatch];
    for (int i = 0; i < kBatch; ++i) in[i] = d[i] < 0.0f ? 1.0f : 0.0f;
    if (cols == 8 && rows == 8) {
        for (int r = 0; r < 8; ++r) std::memcpy(c.px + size_t(by + r) * c.w + bx, in + r * 8, 8 * sizeof(float));
    } else {
        for (int r = 0; r < rows; ++r) std::copy_n(in + r * cols, cols, c.px + size_t(by + r) * c.w + bx);
    }
    s.points += uint64_t(n);
}

// The x and y inputs of the 8 x 8 leaf at (bx, by): a full one's rows of the tables made
// once a render (block_inputs), else its points in order written to xs and ys (kBatch
// each), the lanes past them repeating the last (as the VM pads a batch).
void leaf_inputs(const Ctx& c, int bx, int by, float* xs, float* ys, const float*& px, const float*& py) {
    const int cols = std::min(bx + 8, c.w) - bx, rows = std::min(by + 8, c.h) - by;
    if (cols == 8 && rows == 8) {  // the common case
        px = c.xb.data() + size_t(bx) * 8;
        py = c.yb.data() + size_t(by) * 8;
        return;
    }
    for (int i = 0; i < kBatch; ++i) {
        const int p = std::min(i, cols * rows - 1);
        xs[i] = c.xc[size_t(bx + p % cols)];
        ys[i] = c.yc[size_t(by + p / cols)];
    }
    px = xs;
    py = ys;
}

// Pixels of the tile [x0, x0 + size)^2 (clipped), 8 x 8 pixels per VM batch.
void leaf(Ctx& c, Scratch& s, const TapeView& tape, int x0, int y0, int size) {
    alignas(64) static const float zs[kBatch] = {};  // a 2D model's z
    for (int by = y0; by < std::min(y0 + size, c.h); by += 8)
        for (int bx = x0; bx < std::min(x0 + size, c.w); bx += 8) {
            const int n = (std::min(bx + 8, c.w) - bx) * (std::min(by + 8, c.h) - by);
            alignas(64) float xs[kBatch], ys[kBatch];
            const float *px, *py;
            leaf_inputs(c, bx, by, xs, ys, px, py);
            s.ev.eval(tape, px, py, zs, n, c.time);
            write_leaf(c, s, s.ev.output(tape), bx, by);
        }
}

// The children of a tile after split(): their origins, which need subdividing (todo) and
// which are inside (filled white by descend()); their tapes are in the scratch's batch.
struct Children {
    int child = 0, n = 0, m = 0;
    bool leaves = false;
    int cx[kIvLanes], cy[kIvLanes], todo[kIvLanes];
    uint64_t inside = 0;
    // The children run as tasks: each simplifies its own tape, in parallel, instead of all
    // of them before the tasks start.
    bool tasks = false;
    bool sweep = false;  // the leaves run by SweepVM from the tile's masks (else their traces)
    const Tape* parent = nullptr;
    const IntervalEvaluator* iv = nullptr;
};

// Whether the tiles at `depth` are leaves or the last to be split (their children are
// leaves): their tapes are then traces (simplify_batch without compact) in their parent's
// registers, where they are made at all (leaves run by the sweep get none). Such a tape is
// simplified once more at most, so compacting it costs more than it saves (prospero.vm
// 1024^2: 0.926x the time on 2 threads, 0.937x on 1; with the sweep, 1.05-1.09x).
bool last_split(const Ctx& c, int depth) { return size_t(depth) + 2 >= c.sizes.size(); }

// Evaluates the children of the tile [x0, x0 + size)^2 (clipped to the image) at depth
// `depth`, whose tape is `t`, and simplifies the tape for those that straddle the surface.
// Writes no pixel.
void split(Ctx& c, Scratch& s, int depth, Tape& t, int x0, int y0, Children& ch) {
    const int size = c.sizes[size_t(depth)];
    // (The root, shared by concurrent renders, was linked once by Raster2d: if that failed, a
    // tape reading unwritten registers, it stays unlinked and is copied as is.)
    if (!t.linked && depth > 0) t.link();
    ch.child = c.sizes[size_t(depth) + 1];
    ch.leaves = size_t(depth) + 2 == c.sizes.size();
    const int child = ch.child, per_axis = size / child;
    float bx[6][kIvLanes];  // lanes >= n are never read (the evaluators pad from lane n - 1)
    int n = 0;
    for (int j = 0; j < per_axis; ++j) {
        const int ty = y0 + j * child;
        if (ty >= c.h) break;
        const int ty1 = std::min(ty + child, c.h) - 1;
        for (int i = 0; i < per_axis; ++i) {
            const int tx = x0 + i * child;
            if (tx >= c.w) break;
            const int tx1 = std::min(tx + child, c.w) - 1;
            bx[0][n] = c.xc[size_t(tx)];
            bx[1][n] = c.xc[size_t(tx1)];
            bx[2][n] = c.yc[size_t(ty1)];  // y decreases downwards
            bx[3][n] = c.yc[size_t(ty)];
            bx[4][n] = 0.0f;
            bx[5][n] = 0.0f;
            ch.cx[n] = tx;
            ch.cy[n] = ty;
            ++n;
        }
    }
    ch.n = n;
    IntervalEvaluator& iv = s.interval(depth);
    iv.eval(t, bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], n, c.time);
    ch.m = 0;
    ch.inside = 0;
    uint64_t lanes = 0;
    for (int k = 0; k < n; ++k) {
        const Interval r = iv.result(k);
        if (r.hi < 0.0f) {
            ch.inside |= uint64_t(1) << k;
        } else if (!(r.lo >= 0.0f)) {  // straddles the surface, or unknown (NaN)
            ch.todo[ch.m++] = k;
            lanes |= uint64_t(1) << k;
        }
        // else: outside, and the image starts black
    }
    ch.tasks = child >= 64 && ch.m > 1 && !ch.leaves && c.nested(depth);
    ch.parent = &t;
    ch.iv = &iv;
    // The leaves run in one sweep from the tile's tape and masks (no traces made); children
    // that run as tasks each simplify their own tape.
    ch.sweep = ch.leaves && lanes != 0 && t.linked && t.out_def != Tape::kNone;
    if (ch.sweep) simplify_masks(t, iv.choices(), iv.stride(), lanes, s.batch[size_t(depth)]);
    else if (!ch.tasks) simplify_batch(t, iv.choices(), iv.stride(), lanes, s.batch[size_t(depth)], /*compact=*/!last_split(c, depth + 1));
}

void process(Ctx& c, Scratch& s, int depth, Tape& t, int x0, int y0);

void give_back(Ctx& c, Scratch* s) {
    c.points += s->points;
    s->points = 0;
    c.pool->release(s);
}

// Fills the inside children of a split() tile and processes the others.
void descend(Ctx& c, Scratch& s, int depth, const Children& ch) {
    const int child = ch.child;
    for (uint64_t in = ch.inside; in; in &= in - 1) {
        const int k = __builtin_ctzll(in);
        fill(c, ch.cx[k], ch.cy[k], std::min(ch.cx[k] + child, c.w), std::min(ch.cy[k] + child, c.h), 1.0f);
    }
    const BatchScratch& bs = s.batch[size_t(depth)];
    if (ch.sweep) {
        const float* xs[kIvLanes];
        const float* ys[kIvLanes];
        uint64_t lanes = 0;
        for (int q = 0; q < ch.m; ++q) {
            const int k = ch.todo[q];
            lanes |= uint64_t(1) << k;
            const int bx = ch.cx[k], by = ch.cy[k];
            // The leaf's rows of the picture, fetched while the sweep runs: written after it,
            // they missed the cache (prospero.vm 0.94x-0.96x the time).
            for (int r = 0; r < std::min(by + 8, c.h) - by; ++r) __builtin_prefetch(c.px + size_t(by + r) * c.w + bx, 1, 3);
            if (s.edge.size() < size_t(2 * kBatch * kIvLanes)) s.edge.resize(size_t(2 * kBatch * kIvLanes));
            float* ex = s.edge.data() + size_t(2 * kBatch * k);  // (a leaf cut by the image's edge)
            leaf_inputs(c, bx, by, ex, ex + kBatch, xs[k], ys[k]);
        }
        s.sweep.eval(*ch.parent, ch.iv->choices(), ch.iv->stride(), bs.mask.data(), lanes, xs, ys, nullptr, c.time);
        for (int q = 0; q < ch.m; ++q) {
            const int k = ch.todo[q];
            write_leaf(c, s, s.sweep.output(k), ch.cx[k], ch.cy[k]);
        }
        return;
    }
    if (ch.leaves) {
        for (int q = 0; q < ch.m; ++q) {
            const int k = ch.todo[q];
            leaf(c, s, bs.view(k), ch.cx[k], ch.cy[k], child);
        }
        return;
    }
    if (ch.tasks) {
        tbb::parallel_for(0, ch.m, [&](int q) {
            const int k = ch.todo[q];
            Scratch* s2 = c.pool->acquire();
            Tape& ct = s2->tapes[size_t(depth) + 1];
            simplify(*ch.parent, ch.iv->choices(), ch.iv->stride(), k, ct, s2->lane);
            process(c, *s2, depth + 1, ct, ch.cx[k], ch.cy[k]);
            give_back(c, s2);
        });
        return;
    }
    Tape& ct = s.tapes[size_t(depth) + 1];
    for (int q = 0; q < ch.m; ++q) {
        const int k = ch.todo[q];
        ct.assign(bs.code(k), bs.len[size_t(k)], bs.out[size_t(k)], bs.regs[size_t(k)]);
        process(c, s, depth + 1, ct, ch.cx[k], ch.cy[k]);
    }
}

// The tile [x0, x0 + size)^2 (clipped to the image) at depth `depth`, whose tape is `t`.
void process(Ctx& c, Scratch& s, int depth, Tape& t, int x0, int y0) {
    if (size_t(depth) + 1 == c.sizes.size()) {
        leaf(c, s, t.view(), x0, y0, c.sizes[size_t(depth)]);
        return;
    }
    Children ch;
    split(c, s, depth, t, x0, y0, ch);
    descend(c, s, depth, ch);
}

// Every column's coord_x and every row's coord_y, for both ways of drawing the image.
void pixel_grid(int w, int h, std::vector<float>& xc, std::vector<float>& yc) {
    xc.resize(size_t(w));
    yc.resize(size_t(h));
    for (int i = 0; i < w; ++i) xc[size_t(i)] = coord_x(i, w);
    for (int j = 0; j < h; ++j) yc[size_t(j)] = coord_y(j, h);
}

// Ctx::xb / yb: for each full block of 8 columns (rows), the 64 lanes' x (y) in leaf order
// (lane r * 8 + q is pixel (bx + q, by + r)).
void block_inputs(Ctx& c) {
    c.xb.assign(size_t(c.w / kLeaf) * kBatch, 0.0f);
    c.yb.assign(size_t(c.h / kLeaf) * kBatch, 0.0f);
    for (int b = 0; b < c.w / kLeaf; ++b)
        for (int r = 0; r < kLeaf; ++r)
            for (int q = 0; q < kLeaf; ++q) c.xb[size_t(b) * kBatch + size_t(r * kLeaf + q)] = c.xc[size_t(b * kLeaf + q)];
    for (int b = 0; b < c.h / kLeaf; ++b)
        for (int r = 0; r < kLeaf; ++r)
            for (int q = 0; q < kLeaf; ++q) c.yb[size_t(b) * kBatch + size_t(r * kLeaf + q)] = c.yc[size_t(b * kLeaf + r)];
}

// At most `threads` worker threads while it lives (0: all).
std::unique_ptr<tbb::global_control> thread_limit(int threads) {
    if (threads <= 0) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
}

// The brute-force image: every pixel through the full program, rows of 64-point batches.
Image render_brute(const CompiledScene& scene, const std::vector<float>& xc, const std::vector<float>& yc,
                   RenderStats* stats) {
    const int w = int(xc.size()), h = int(yc.size());
    Image img(w, h, 1);
    float* px = img.pixels.data();
    std::atomic<uint64_t> points{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, h, 4), [&](const tbb::blocked_range<int>& r) {
        Evaluator ev(scene.distance);
        float xs[kBatch], ys[kBatch], zs[kBatch] = {};
        for (int y = r.begin(); y < r.end(); ++y) {
            const float yv = yc[size_t(y)];
            for (int x0 = 0; x0 < w; x0 += kBatch) {
                const int n = std::min(kBatch, w - x0);
                for (int i = 0; i < n; ++i) {
                    xs[i] = xc[size_t(x0 + i)];
                    ys[i] = yv;
                }
                ev.eval(xs, ys, zs, n, scene.time);
                const float* d = ev.output(0);
                float* row = px + size_t(y) * w + x0;
                for (int i = 0; i < n; ++i) row[i] = d[i] < 0.0f ? 1.0f : 0.0f;
            }
        }
        points += uint64_t(r.size()) * uint64_t(w);
    });
    if (stats) stats->distance_points = stats->distance_points_by[RenderStats::kRays] = points;
    return img;
}

}  // namespace

struct Raster2d::Prepared {
    explicit Prepared(const CompiledScene& s) : scene(s), root(Tape::from(s.distance, 0)), pool(s.distance, root) {
        root.mark_sign_only();  // a pixel only asks "< 0"
    }
    const CompiledScene& scene;
    Tape root;
    mutable Pool pool;  // thread-safe; its scratch objects outlive each render
};

Raster2d::Raster2d(const CompiledScene& scene) : p_(std::make_unique<Prepared>(scene)) {}
Raster2d::~Raster2d() = default;

Image Raster2d::render(int w, int h, int threads, RenderStats* stats) const {
    w = std::max(w, 1);
    h = std::max(h, 1);
    const auto limit = thread_limit(threads);
    Pool& pool = p_->pool;
    Ctx c{w, h, nullptr, p_->scene.time, &pool};
    c.threads = threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
    pixel_grid(w, h, c.xc, c.yc);

    int size = kLeaf;
    while (size < w || size < h) size *= 2;
    c.sizes.push_back(size);
    // 4 x 4 children while tiles are >= 128 pixels, then 8 x 8 leaves of 8 x 8 pixels
    // (1024: 1024 -> 256 -> 64 -> 8). Measured against 16-pixel leaves and other splits
    // (instruction counts under callgrind): the cheapest for prospero.vm.
    while (c.sizes.back() >= 128) c.sizes.push_back(c.sizes.back() / 4);
    if (c.sizes.back() > kLeaf) c.sizes.push_back(kLeaf);
    // The image's allocation (zeroing 4 bytes a pixel) and the leaves' input rows overlap the
    // top level's work.
    Image img;
    Scratch* s = nullptr;
    Children top;
    Tape& root = p_->root;  // (split() only reads a linked tape)
    tbb::parallel_invoke(
        [&] {
            img = Image(w, h, 1);
            block_inputs(c);
        },
        [&] {
            s = pool.acquire();
            if (c.sizes.size() > 1) split(c, *s, 0, root, 0, 0, top);
        });
    c.px = img.pixels.data();
    if (c.sizes.size() > 1) descend(c, *s, 0, top);
    else process(c, *s, 0, root, 0, 0);
    give_back(c, s);
    if (stats) stats->distance_points = stats->distance_points_by[RenderStats::kRays] = c.points;
    return img;
}

Image render_2d(const CompiledScene& scene, int w, int h, int threads, bool baseline, RenderStats* stats) {
    if (!baseline) return Raster2d(scene).render(w, h, threads, stats);
    const auto limit = thread_limit(threads);
    std::vector<float> xc, yc;
    pixel_grid(std::max(w, 1), std::max(h, 1), xc, yc);
    return render_brute(scene, xc, yc, stats);
}

}  // namespace sdfc
