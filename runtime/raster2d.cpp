// The Prospero image of a 2D field (render_2d, declared in runtime/slice.hpp): a quadtree
// over the image with interval arithmetic and per-tile tape simplification.
//
//   whole image (N = power of two >= w, h)
//     -> 4x4 tiles of N/4 ... (while tiles are >= 128 pixels), then 8x8 tiles of 8 pixels
//   Each level evaluates all children of a tile at once (one interval lane per child) with
//   the tile's tape. A child whose interval is < 0 is filled white, one >= 0 black; the
//   others get their own shorter tape (simplify()) and are subdivided, down to 8x8 pixel
//   tiles, evaluated as one 64-lane VM batch.
//
// Exactness: the interval bounds enclose the VM's float results bit for bit, and a
// simplified tape computes the same floats as its parent inside its tile (see
// runtime/interval.hpp), so the image is identical to brute-force evaluation
// (tests/runtime/test_raster2d.cpp checks it pixel by pixel).
#include <algorithm>
#include <atomic>
#include <memory>
#include <mutex>
#include <vector>
#include <cstdio>
#include <chrono>
#include <cstdlib>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "runtime/interval.hpp"
#include "runtime/slice.hpp"
#include "runtime/vm.hpp"

// GCC cannot see that the evaluators read only the first n lanes of their inputs.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace sdfc {
namespace {
std::atomic<uint64_t> g_ns[16], g_ivns[16], g_leafns[16];
std::atomic<uint64_t> g_calls[16], g_in[16], g_out[16], g_iv[16], g_ivl[16];

// Pixel coordinates, shared by every path so they produce the same floats. Both are
// monotonic in the pixel index, so a tile's coordinate interval is its corner pixels'.
inline float coord_x(int i, int w) { return w > 1 ? -1.0f + 2.0f * float(i) / float(w - 1) : 0.0f; }
inline float coord_y(int j, int h) { return h > 1 ? 1.0f - 2.0f * float(j) / float(h - 1) : 0.0f; }

constexpr int kLeaf = 8;       // leaf tiles: 8 x 8 pixels = one VM batch
constexpr int kMaxDepth = 12;  // 2^12 * 8 pixels: far beyond any image size we accept
static_assert(kLeaf * kLeaf == kBatch);

struct Scratch {
    Scratch(const Program& prog, const Tape& root) : ev(prog), root_regs(root.num_regs), root_choices(root.choices) {
        iv.resize(kMaxDepth);
        tapes.resize(kMaxDepth + 1);
    }
    IntervalEvaluator& interval(int depth) {
        auto& p = iv[size_t(depth)];
        if (!p) p = std::make_unique<IntervalEvaluator>(root_regs, root_choices);
        return *p;
    }
    Evaluator ev;
    uint32_t root_regs, root_choices;
    std::vector<std::unique_ptr<IntervalEvaluator>> iv;  // per depth: the choices stay readable while children run
    std::vector<Tape> tapes;                             // per depth: the tape of the tile being processed
    SimplifyScratch ss;
    uint64_t points = 0;
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
    uint64_t points() const {
        uint64_t n = 0;
        for (const auto& s : all_) n += s->points;
        return n;
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
    std::vector<int> sizes;  // tile size per depth: sizes[0] the root, the last the leaves
    bool simplify_leaves = true;
};

void fill(Ctx& c, int x0, int y0, int x1, int y1, float v) {
    for (int y = y0; y < y1; ++y) std::fill(c.px + size_t(y) * c.w + x0, c.px + size_t(y) * c.w + x1, v);
}

// Pixels of the tile [x0, x0 + size)^2 (clipped), 8 x 8 pixels per VM batch.
void leaf(Ctx& c, Scratch& s, const Tape& t, int x0, int y0, int size) {
    for (int by = y0; by < std::min(y0 + size, c.h); by += 8)
        for (int bx = x0; bx < std::min(x0 + size, c.w); bx += 8) {
            const int x1 = std::min(bx + 8, c.w), y1 = std::min(by + 8, c.h);
            const int cols = x1 - bx, rows = y1 - by, n = cols * rows;
            float xs[kBatch], ys[kBatch], zs[kBatch];  // lanes >= n are never read
            std::fill_n(zs, n, 0.0f);
            for (int r = 0; r < rows; ++r) {
                const float yv = coord_y(by + r, c.h);
                for (int q = 0; q < cols; ++q) {
                    xs[r * cols + q] = coord_x(bx + q, c.w);
                    ys[r * cols + q] = yv;
                }
            }
            s.ev.eval_code(t.code.data(), t.code.size(), xs, ys, zs, n, c.time);
            const float* d = s.ev.reg_data(t.out);
            for (int r = 0; r < rows; ++r) {
                float* row = c.px + size_t(by + r) * c.w + bx;
                for (int q = 0; q < cols; ++q) row[q] = d[r * cols + q] < 0.0f ? 1.0f : 0.0f;
            }
            s.points += uint64_t(n);
        }
}

// The tile [x0, x0 + size)^2 (clipped to the image) at recursion depth `depth`, whose tape
// is `t`, on scratch `s`.
void process(Ctx& c, Scratch& s, int depth, Tape& t, int x0, int y0) {
    const int size = c.sizes[size_t(depth)];
    if (size_t(depth) + 1 == c.sizes.size()) {
        leaf(c, s, t, x0, y0, size);
        return;
    }
    if (!t.linked) t.link();
    const int child = c.sizes[size_t(depth) + 1];
    const int per_axis = size / child;
    const bool child_is_leaf = size_t(depth) + 2 == c.sizes.size();
    float bx[6][kIvLanes];  // lanes >= n are never read (the evaluators pad from lane n - 1)
    int cx[kIvLanes], cy[kIvLanes];
    int n = 0;
    for (int j = 0; j < per_axis; ++j) {
        const int ty = y0 + j * child;
        if (ty >= c.h) break;
        const int ty1 = std::min(ty + child, c.h) - 1;
        for (int i = 0; i < per_axis; ++i) {
            const int tx = x0 + i * child;
            if (tx >= c.w) break;
            const int tx1 = std::min(tx + child, c.w) - 1;
            bx[0][n] = coord_x(tx, c.w);
            bx[1][n] = coord_x(tx1, c.w);
            bx[2][n] = coord_y(ty1, c.h);  // y decreases downwards
            bx[3][n] = coord_y(ty, c.h);
            bx[4][n] = 0.0f;
            bx[5][n] = 0.0f;
            cx[n] = tx;
            cy[n] = ty;
            ++n;
        }
    }
    IntervalEvaluator& iv = s.interval(depth);
    iv.eval(t, bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], n, c.time);
    g_iv[depth] += t.code.size(); g_ivl[depth] += n;
    int todo[kIvLanes], m = 0;
    for (int k = 0; k < n; ++k) {
        const Interval r = iv.result(k);
        if (r.hi < 0.0f) fill(c, cx[k], cy[k], std::min(cx[k] + child, c.w), std::min(cy[k] + child, c.h), 1.0f);
        else if (!(r.lo >= 0.0f)) todo[m++] = k;  // straddles the surface, or unknown (NaN)
        // else: outside, and the image starts black
    }
    if (child >= 64 && m > 1) {
        tbb::parallel_for(0, m, [&](int q) {
            const int k = todo[q];
            Scratch* s2 = c.pool->acquire();
            Tape& ct = s2->tapes[size_t(depth) + 1];
            simplify(t, iv.choices(), iv.stride(), k, ct, s2->ss);
            g_calls[depth]++; g_in[depth] += t.code.size(); g_out[depth] += ct.code.size();
            process(c, *s2, depth + 1, ct, cx[k], cy[k]);
            c.pool->release(s2);
        });
        return;
    }
    Tape& ct = s.tapes[size_t(depth) + 1];
    for (int q = 0; q < m; ++q) {
        const int k = todo[q];
        if (child_is_leaf && !c.simplify_leaves) {
            leaf(c, s, t, cx[k], cy[k], child);
            continue;
        }
        simplify(t, iv.choices(), iv.stride(), k, ct, s.ss);
        g_calls[depth]++; g_in[depth] += t.code.size(); g_out[depth] += ct.code.size();
        process(c, s, depth + 1, ct, cx[k], cy[k]);
    }
}

}  // namespace

Image render_2d(const CompiledScene& scene, int w, int h, int threads, bool baseline, RenderStats* stats) {
    w = std::max(w, 1);
    h = std::max(h, 1);
    Image img(w, h, 1);
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    const Program& prog = scene.distance;
    Ctx c{w, h, img.pixels.data(), scene.time, nullptr};

    if (baseline) {
        // Brute force: every pixel through the full program, rows of 64-point batches.
        std::atomic<uint64_t> points{0};
        tbb::parallel_for(tbb::blocked_range<int>(0, h, 4), [&](const tbb::blocked_range<int>& r) {
            Evaluator ev(prog);
            float xs[kBatch], ys[kBatch], zs[kBatch] = {};
            for (int y = r.begin(); y < r.end(); ++y) {
                const float yv = coord_y(y, h);
                for (int x0 = 0; x0 < w; x0 += kBatch) {
                    const int n = std::min(kBatch, w - x0);
                    for (int i = 0; i < n; ++i) {
                        xs[i] = coord_x(x0 + i, w);
                        ys[i] = yv;
                    }
                    ev.eval(xs, ys, zs, n, scene.time);
                    const float* d = ev.output(0);
                    float* row = c.px + size_t(y) * w + x0;
                    for (int i = 0; i < n; ++i) row[i] = d[i] < 0.0f ? 1.0f : 0.0f;
                }
            }
            points += uint64_t(r.size()) * uint64_t(w);
        });
        if (stats) stats->distance_points = points;
        return img;
    }

    Tape root = Tape::from(prog, 0);
    Pool pool(prog, root);
    c.pool = &pool;
    int size = kLeaf;
    while (size < w || size < h) size *= 2;
    c.sizes.push_back(size);
    if (const char* e = std::getenv("SDFC_2D_SCHEDULE")) {
        for (const char* p = e; *p;) {
            int v = std::atoi(p);
            if (v > 0 && v < c.sizes.back()) c.sizes.push_back(v);
            while (*p && *p != ',') ++p;
            if (*p) ++p;
        }
    } else {
        while (c.sizes.back() >= 128) c.sizes.push_back(c.sizes.back() / 4);
        if (c.sizes.back() > kLeaf) c.sizes.push_back(kLeaf);
    }
    if (const char* e = std::getenv("SDFC_2D_LEAFSIMP")) c.simplify_leaves = std::atoi(e) != 0;
    Scratch* s = pool.acquire();
    process(c, *s, 0, root, 0, 0);
    pool.release(s);
    if (stats) stats->distance_points = pool.points();
    if (std::getenv("SDFC_DEBUG2D")) for (int d = 0; d < 6; ++d) if (g_calls[d] || g_iv[d] || g_leafns[d]) std::fprintf(stderr, "depth %d: iv %.2fms simp %.2fms leaf %.2fms | iv instrs %lu lanes %lu | simplify calls %lu in %lu out %lu\n", d, g_ivns[d]*1e-6, g_ns[d]*1e-6, g_leafns[d]*1e-6, (unsigned long)g_iv[d], (unsigned long)g_ivl[d], (unsigned long)g_calls[d], (unsigned long)g_in[d], (unsigned long)g_out[d]);
    for (int d = 0; d < 16; ++d) g_ns[d] = g_ivns[d] = g_leafns[d] = g_calls[d] = g_in[d] = g_out[d] = g_iv[d] = g_ivl[d] = 0;
    return img;
}

}  // namespace sdfc
