// Building a family of rays' columns (ray_columns.hpp): each leaf not proven empty is
// projected onto the plane of the columns' cells (along the light, or from the eye: a
// rectangle of cells holds its box's projection) and gives every column it covers the run
// of depth its box spans (a light's: its chord through the column, less the pieces its tape
// proves positive); a column's runs are then sorted and merged.
#include "runtime/cpu/ray_columns.hpp"

#include <algorithm>
#include <cstring>
#include <mutex>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "compiler/render/rules.h"
#include "runtime/eval/interval.hpp"

namespace sdfc::cpu {

namespace {

// The most cells across (a column per cell: memory and build time grow with its square),
// and of leaves' rectangles' cells in all (the build's time).
constexpr int kMaxCells = 1024;
constexpr size_t kMaxEntries = size_t(4) << 20;
// A light's chords are cut into pieces about kPiece cells long (at most kMaxPieces), each
// proven positive or kept, in leaves of at most kProvableTape instructions (as
// Worker::segment_bounds: over a longer tape a proof costs more than the jumps it saves).
// colonnade.vm: 0.5 and 8 took 0.94x the time of 1 and 4 by medians; 0.25 and 16, 0.97x
// that again, but a longer build.
constexpr double kPiece = 0.5;
constexpr int kMaxPieces = 8;
constexpr uint32_t kProvableTape = 64;

// A leaf's box (margins included) and the rectangle of cells [u0, u1] x [v0, v1] that holds
// its projection; [s0, s1], the depths its box spans.
struct Span {
    float s0, s1;
    int u0, u1, v0, v1;
    glm::vec3 lo, hi;
    uint32_t leaf;
};

// Each column gets the span's depths in every cell of its rectangle: in the order of their
// starts, so that each column's runs come sorted and merge as they arrive; one pass counts
// the merged runs, the next writes them. (A camera's columns: the boxes seen from the eye.)
void lay_spans(RayColumns& c, std::vector<Span>& spans) {
    const size_t columns = size_t(c.nu) * size_t(c.nv);
    std::sort(spans.begin(), spans.end(), [](const Span& p, const Span& q) { return p.s0 < q.s0; });
    auto each_cell = [&](const Span& S, auto&& fn) {  // fn(column) for the cells of S's rectangle
        for (int y = S.v0; y <= S.v1; ++y)
            for (size_t k = size_t(y) * c.nu + S.u0, ke = size_t(y) * c.nu + S.u1; k <= ke; ++k) fn(k);
    };
    std::vector<float> end(columns, -INFINITY);
    std::vector<uint32_t> start(columns + 1, 0);
    for (const Span& S : spans)
        each_cell(S, [&](size_t k) {
            start[k + 1] += S.s0 > end[k];
            end[k] = std::max(end[k], S.s1);
        });
    // Room for each column's runs and its end mark, after the empty columns' mark.
    for (size_t k = 0; k < columns; ++k) start[k + 1] += start[k] + (start[k + 1] > 0);
    const glm::vec2 mark(INFINITY, INFINITY);
    c.runs.assign(start[columns] + 1, mark);
    c.first.resize(columns);
    std::vector<uint32_t> next(columns);
    for (size_t k = 0; k < columns; ++k) {
        const bool empty = start[k + 1] == start[k];
        c.first[k] = empty ? 0 : start[k] + 1;
        next[k] = c.first[k];
    }
    for (const Span& S : spans)
        each_cell(S, [&](size_t k) {
            if (next[k] > c.first[k] && S.s0 <= c.runs[next[k] - 1].y) c.runs[next[k] - 1].y = std::max(c.runs[next[k] - 1].y, S.s1);
            else c.runs[next[k]++] = glm::vec2(S.s0, S.s1);
        });
}

// Depths [run.x, run.y] along the rays of one column.
struct Chord {
    uint32_t column;
    glm::vec2 run;
};

// 1 / k for the pieces of a chord.
constexpr double kInverse[kMaxPieces + 1] = {0.0, 1.0, 1.0 / 2, 1.0 / 3, 1.0 / 4, 1.0 / 5, 1.0 / 6, 1.0 / 7, 1.0 / 8};

// Lays the chords of spans (lay_chords), one task's share of them: its own interval
// evaluator and list.
class ChordLayer {
public:
    ChordLayer(const RayColumns& c, const TapeTree& T, float g) : c_(c), T_(T), g_(g), iv_(T.max_regs, 64) {
        cell_ = 1.0 / double(c.inv_cell);
        inv_piece_ = 1.0 / (kPiece * cell_);
        const double half = 0.5 * cell_ + double(g);
        for (int a = 0; a < 3; ++a) {
            U_[a] = c.u[a], V_[a] = c.v[a], D_[a] = c.dir[a];
            spread_[a] = half * (std::abs(U_[a]) + std::abs(V_[a]));
            inv_[a] = std::abs(D_[a]) > 1e-6 ? 1.0 / D_[a] : 0.0;
        }
    }
    std::vector<Chord> chords;

    void lay(const Span& S) {
        leaf_ = &T_.leaves[S.leaf];
        const bool provable = leaf_->len <= kProvableTape && leaf_->ivhi > 0.0f;  // (a leaf all inside has no positive piece)
        for (int y = S.v0; y <= S.v1; ++y)
            for (int x = S.u0; x <= S.u1; ++x) {
                const double cu = double(c_.u0) + (x + 0.5) * cell_, cv = double(c_.v0) + (y + 0.5) * cell_;
                double lo = S.s0, hi = S.s1, mid[3];
                bool meets = true;
                for (int a = 0; a < 3; ++a) {
                    mid[a] = cu * U_[a] + cv * V_[a];
                    const double cmin = mid[a] - spread_[a], cmax = mid[a] + spread_[a];
                    if (inv_[a] > 0.0) lo = std::max(lo, (S.lo[a] - cmax) * inv_[a]), hi = std::min(hi, (S.hi[a] - cmin) * inv_[a]);
                    else if (inv_[a] < 0.0) lo = std::max(lo, (S.hi[a] - cmin) * inv_[a]), hi = std::min(hi, (S.lo[a] - cmax) * inv_[a]);
                    else meets = meets && cmax >= S.lo[a] && cmin <= S.hi[a];  // (the slab holds the cell or not)
                }
                if (!meets || !(lo <= hi)) continue;
                const uint32_t column = uint32_t(size_t(y) * c_.nu + size_t(x));
                if (!provable) {
                    chords.push_back(Chord{column, glm::vec2(float(lo) - g_, float(hi) + g_)});
                    continue;
                }
                // Piece j spans depths lo + [j, j + 1] len; per axis its box is piece 0's moved
                // by j steps, widened by the cell's spread and g twice (the depths' margin, and
                // the rounding of these floats).
                const int k = std::clamp(int(std::ceil((hi - lo) * inv_piece_)), 1, kMaxPieces);
                const double len = (hi - lo) * kInverse[k];
                float blo[3], bhi[3], step[3], at[kMaxPieces + 1];  // at: the pieces' ends
                for (int ax = 0; ax < 3; ++ax) {
                    const double e0 = mid[ax] + lo * D_[ax], e1 = e0 + len * D_[ax], pad = spread_[ax] + 2.0 * double(g_);
                    blo[ax] = float(std::min(e0, e1) - pad), bhi[ax] = float(std::max(e0, e1) + pad), step[ax] = float(len * D_[ax]);
                }
                for (int j = 0; j < k; ++j) at[j] = float(lo + j * len);
                at[k] = float(hi);
                for (int j = 0; j < k; ++j) {
                    for (int ax = 0; ax < 3; ++ax) {
                        bx_[2 * ax][np_] = std::max(blo[ax] + float(j) * step[ax], S.lo[ax]);
                        bx_[2 * ax + 1][np_] = std::min(bhi[ax] + float(j) * step[ax], S.hi[ax]);
                    }
                    piece_[np_++] = Chord{column, glm::vec2(at[j] - g_, at[j + 1] + g_)};
                    if (np_ == kIvLanes) prove();
                }
            }
        prove();
    }

private:
    // The pieces gathered (all of leaf_'s): those not proven positive are kept, each joined
    // to the one before when they touch (the pieces of a chord come one after another).
    void prove() {
        if (np_ == 0) return;
        iv_.eval(leaf_->view(), bx_[0], bx_[1], bx_[2], bx_[3], bx_[4], bx_[5], np_, T_.time);
        for (int q = 0; q < np_; ++q) {
            const Interval r = iv_.result(q);
            if (raw_floor(r.lo, r.hi) > 0.0f) continue;
            if (!chords.empty() && chords.back().column == piece_[q].column && piece_[q].run.x <= chords.back().run.y)
                chords.back().run.y = std::max(chords.back().run.y, piece_[q].run.y);
            else chords.push_back(piece_[q]);
        }
        np_ = 0;
    }
    const RayColumns& c_;
    const TapeTree& T_;
    const float g_;
    double cell_, inv_piece_, U_[3], V_[3], D_[3], spread_[3], inv_[3];  // spread: how far a cell's points move an axis; inv: 1 / D (0: across the rays)
    IntervalEvaluator iv_;
    const TapeTree::Leaf* leaf_ = nullptr;
    alignas(64) float bx_[6][kIvLanes];
    Chord piece_[kIvLanes];
    int np_ = 0;
};

// Parallel rays: in each cell of its rectangle a box spans only its chord along the rays
// through the cell, far less than its whole depth for a box seen aslant. Each slab of the
// box bounds the chord: a point of the cell (its centre cu, cv +- half, margin g included)
// at depth w is cu u + cv v + w dir, and the slab's entry and exit, linear across the cell,
// are least and greatest at its corners. A chord is cut into pieces about kPiece cells
// long, and a piece whose box (the cell's points over its depths, within the leaf's box)
// the leaf's tape proves positive is left out (no sign change in it; a sheet counts as
// positive, as in the tree): a shadow ray leaving a surface is past its column's run once it
// is past the surface's own piece, not the whole layer of leaves the surface crosses. The
// leaves' chords are laid in parallel, gathered by column (a counting sort), and each
// column's sorted and merged.
void lay_chords(RayColumns& c, const std::vector<Span>& spans, float g, const TapeTree& T) {
    const size_t columns = size_t(c.nu) * size_t(c.nv);
    tbb::enumerable_thread_specific<ChordLayer> layers([&] { return ChordLayer(c, T, g); });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, spans.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
        ChordLayer& layer = layers.local();
        for (size_t i = r.begin(); i != r.end(); ++i) layer.lay(spans[i]);
    });
    // (counted, then placed: afterwards at[k] is where column k's chords end, column k - 1's
    // where they begin)
    std::vector<uint32_t> at(columns + 1, 0);
    for (const ChordLayer& layer : layers)
        for (const Chord& h : layer.chords) ++at[h.column + 1];
    for (size_t k = 0; k < columns; ++k) at[k + 1] += at[k];
    std::vector<glm::vec2> all(at[columns]);
    for (const ChordLayer& layer : layers)
        for (const Chord& h : layer.chords) all[at[h.column]++] = h.run;
    const glm::vec2 mark(INFINITY, INFINITY);
    c.runs.assign(1, mark);  // (the empty columns' mark)
    c.first.assign(columns, 0);
    for (size_t k = 0; k < columns; ++k) {
        const uint32_t begin = k == 0 ? 0 : at[k - 1];
        glm::vec2* r = all.data() + begin;
        const uint32_t n = at[k] - begin;
        if (n == 0) continue;
        for (uint32_t j = 1; j < n; ++j)  // (insertion: a column holds a few)
            for (uint32_t i = j; i > 0 && r[i].x < r[i - 1].x; --i) std::swap(r[i], r[i - 1]);
        c.first[k] = uint32_t(c.runs.size());
        glm::vec2 cur = r[0];
        for (uint32_t j = 1; j < n; ++j) {
            if (r[j].x <= cur.y) cur.y = std::max(cur.y, r[j].y);
            else c.runs.push_back(cur), cur = r[j];
        }
        c.runs.push_back(cur);
        c.runs.push_back(mark);
    }
}

}  // namespace

std::shared_ptr<const RayColumns> build_ray_columns(const TapeTree& T, const ColumnsKey& key) {
    if (!T.active || T.boxes_.empty() || !(glm::dot(key.dir, key.dir) > 0.0f)) return nullptr;
    auto C = std::make_shared<RayColumns>();
    RayColumns& c = *C;
    c.central = key.central;
    // (as the rays hold it, bit for bit: clear_until knows a parallel ray by its direction)
    c.dir = std::abs(glm::dot(key.dir, key.dir) - 1.0f) < 1e-4f ? key.dir : glm::normalize(key.dir);
    if (c.central) {
        c.u = key.u, c.v = key.v, c.eye = key.eye;
    } else {
        // Across the light: any unit vector not along it, then the third by the cross product.
        const glm::vec3 a = std::abs(c.dir.x) < 0.6f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        c.u = glm::normalize(glm::cross(c.dir, a));
        c.v = glm::cross(c.dir, c.u);
    }
    const glm::vec3 au = glm::abs(c.u), av = glm::abs(c.v), ad = glm::abs(c.dir);

    const TapeTree::NodeBox& R = T.boxes_[0];
    const glm::vec3 rlo(R.lo[0], R.lo[1], R.lo[2]), rhi(R.hi[0], R.hi[1], R.hi[2]);
    // A margin over the rounding of the rays' own points and of these projections (as in
    // raw_shadow_cut).
    float big = std::max(rules::sdf_max3(glm::abs(rlo)), rules::sdf_max3(glm::abs(rhi)));
    if (c.central) big = std::max(big, rules::sdf_max3(glm::abs(c.eye)));
    if (!std::isfinite(big)) return nullptr;
    const float g = 1e-5f * (1.0f + big);
    c.root_lo = rlo + g, c.root_hi = rhi - g;

    std::vector<uint32_t> full;  // the leaves not proven empty
    float finest = INFINITY;
    for (uint32_t l = 1; l < T.leaves.size(); ++l) {
        const TapeTree::Leaf& L = T.leaves[l];
        if (L.ivlo > 0.0f) continue;
        full.push_back(l);
        finest = std::min(finest, rules::sdf_max3(glm::vec3(L.hi[0] - L.lo[0], L.hi[1] - L.lo[1], L.hi[2] - L.lo[2])));
    }
    // Each leaf's rectangle in the plane of the cells, and the run of depth its box spans.
    struct Proj {
        float a0, a1, b0, b1, s0, s1;
        glm::vec3 lo{0}, hi{0};  // the box, margins included
        uint32_t leaf = 0;
    };
    std::vector<Proj> proj;
    proj.reserve(full.size());
    float plo_u, phi_u, plo_v, phi_v;  // the plane's part the columns cover
    if (c.central) {
        if (!(key.half_u > 0.0f && key.half_v > 0.0f && key.cells_u > 0 && key.cells_v > 0)) return nullptr;
        plo_u = -key.half_u, phi_u = key.half_u, plo_v = -key.half_v, phi_v = key.half_v;
    } else {
        const glm::vec3 rc = 0.5f * (rlo + rhi), rh = 0.5f * (rhi - rlo);
        const float ru = glm::dot(rh, au) + g, rv = glm::dot(rh, av) + g;
        plo_u = glm::dot(rc, c.u) - ru, phi_u = glm::dot(rc, c.u) + ru, plo_v = glm::dot(rc, c.v) - rv, phi_v = glm::dot(rc, c.v) + rv;
    }
    for (uint32_t l : full) {
        const TapeTree::Leaf& L = T.leaves[l];
        const glm::vec3 lo = glm::vec3(L.lo[0], L.lo[1], L.lo[2]) - g, hi = glm::vec3(L.hi[0], L.hi[1], L.hi[2]) + g;
        Proj P;
        if (c.central) {
            // The box seen from the eye: the tangents of its corners in front bound those of
            // its part in front. A corner on (or near) the eye's plane, or a point where an edge
            // crosses it, stands for points whose tangents run off to infinity on the sides of
            // its offset across the view: a box beside the eye covers the columns on its side
            // only, one around the eye all of them.
            P.a0 = P.b0 = INFINITY, P.a1 = P.b1 = -INFINITY, P.s1 = 0.0f;
            glm::vec3 q[8];
            float w[8];
            bool ahead = false, up_u = false, down_u = false, up_v = false, down_v = false;
            auto on_plane = [&](const glm::vec3& p) {
                const float a = glm::dot(p, c.u), b = glm::dot(p, c.v), d = 1e-3f * glm::length(p) + g;
                up_u = up_u || a >= -d, down_u = down_u || a <= d, up_v = up_v || b >= -d, down_v = down_v || b <= d;
            };
            for (int k = 0; k < 8; ++k) {
                q[k] = glm::vec3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z) - c.eye;
                w[k] = glm::dot(q[k], c.dir);
                const float len = glm::length(q[k]);
                P.s1 = std::max(P.s1, len);
                ahead = ahead || w[k] > 0.0f;
                if (w[k] > 1e-3f * len) {
                    const float a = glm::dot(q[k], c.u) / w[k], b = glm::dot(q[k], c.v) / w[k];
                    P.a0 = std::min(P.a0, a), P.a1 = std::max(P.a1, a), P.b0 = std::min(P.b0, b), P.b1 = std::max(P.b1, b);
                } else if (w[k] >= -1e-3f * len) {
                    on_plane(q[k]);
                }
            }
            for (int k = 0; k < 8; ++k)
                for (int axis = 1; axis < 8; axis <<= 1) {
                    const int j = k | axis;  // (each edge once: from its corner with the bit clear)
                    if ((k & axis) || (w[k] > 0.0f) == (w[j] > 0.0f)) continue;
                    on_plane(q[k] + (q[j] - q[k]) * (w[k] / (w[k] - w[j])));
                }
            P.s0 = glm::length(glm::clamp(c.eye, lo, hi) - c.eye);
            P.s0 = std::max(P.s0 * (1.0f - 1e-6f) - g, 0.0f), P.s1 = P.s1 * (1.0f + 1e-6f) + g;
            if (!ahead) continue;  // (behind the eye: its rays never get there)
            if (!(P.a0 <= P.a1)) {
                P.a0 = plo_u, P.a1 = phi_u, P.b0 = plo_v, P.b1 = phi_v;  // (no corner clearly in front)
            } else {
                const float m = 1e-6f * (1.0f + std::max({std::abs(P.a0), std::abs(P.a1), std::abs(P.b0), std::abs(P.b1)}));
                P.a0 -= m, P.a1 += m, P.b0 -= m, P.b1 += m;
                if (up_u) P.a1 = phi_u;
                if (down_u) P.a0 = plo_u;
                if (up_v) P.b1 = phi_v;
                if (down_v) P.b0 = plo_v;
            }
        } else {
            const glm::vec3 m = 0.5f * (lo + hi), h = 0.5f * (hi - lo);
            const float pu = glm::dot(m, c.u), hu = glm::dot(h, au) + g;
            const float pv = glm::dot(m, c.v), hv = glm::dot(h, av) + g;
            const float ps = glm::dot(m, c.dir), hs = glm::dot(h, ad) + g;
            P = Proj{pu - hu, pu + hu, pv - hv, pv + hv, ps - hs, ps + hs, lo, hi};
        }
        P.leaf = l;
        P.a0 = std::max(P.a0, plo_u), P.a1 = std::min(P.a1, phi_u), P.b0 = std::max(P.b0, plo_v), P.b1 = std::min(P.b1, phi_v);
        if (!(P.a0 <= P.a1 && P.b0 <= P.b1 && P.s0 <= P.s1)) continue;  // (no column of the family meets it; NaN)
        proj.push_back(P);
    }

    // Cells as small as the finest leaf (a light's) or about 2 x 2 pixels (the camera's),
    // but at most kMaxCells across and, over all the leaves, kMaxEntries rectangle cells
    // (a tree left coarse by its budget: bigger cells, a bounded build).
    const float span_u = phi_u - plo_u, span_v = phi_v - plo_v;
    float cell = c.central ? std::max(span_u / float(key.cells_u), span_v / float(key.cells_v))
                           : (std::isfinite(finest) ? finest : std::max(span_u, span_v));
    cell = std::max(cell, std::max(span_u, span_v) / float(kMaxCells));
    if (!(cell > 0.0f) || !std::isfinite(cell)) return nullptr;
    for (int k = 0; k < 16; ++k) {
        double entries = 0.0;
        for (const Proj& P : proj)
            entries += (std::floor((P.a1 - plo_u) / cell) - std::floor((P.a0 - plo_u) / cell) + 1.0) *
                       (std::floor((P.b1 - plo_v) / cell) - std::floor((P.b0 - plo_v) / cell) + 1.0);
        if (entries <= double(kMaxEntries)) break;
        cell *= 2.0f;
    }
    c.u0 = plo_u, c.v0 = plo_v;
    c.inv_cell = 1.0f / cell;
    c.nu = std::clamp(int(std::ceil(span_u * c.inv_cell)) + 1, 1, kMaxCells + 2);
    c.nv = std::clamp(int(std::ceil(span_v * c.inv_cell)) + 1, 1, kMaxCells + 2);

    std::vector<Span> spans;
    spans.reserve(proj.size());
    auto cell_of = [](float x, float x0, float inv, int n) { return std::clamp(int(std::floor((x - x0) * inv)), 0, n - 1); };
    for (const Proj& P : proj)
        spans.push_back(Span{P.s0, P.s1, cell_of(P.a0, c.u0, c.inv_cell, c.nu), cell_of(P.a1, c.u0, c.inv_cell, c.nu),
                             cell_of(P.b0, c.v0, c.inv_cell, c.nv), cell_of(P.b1, c.v0, c.inv_cell, c.nv), P.lo, P.hi, P.leaf});
    if (c.central) lay_spans(c, spans);
    else lay_chords(c, spans, g, T);
    return C;
}

namespace {

// The columns built last, for the renders after them with the same tree and light (the
// frames of a still camera, `sdfc bench`'s repeats). The tree is held weakly: a new tree
// at a freed tree's address must not match.
struct KeptColumns {
    std::weak_ptr<const TapeTree> tree;
    ColumnsKey key;
    std::shared_ptr<const RayColumns> columns;
};

bool same_key(const ColumnsKey& a, const ColumnsKey& b) {
    auto same = [](const glm::vec3& p, const glm::vec3& q) { return std::memcmp(&p, &q, sizeof p) == 0; };
    return a.central == b.central && same(a.dir, b.dir) && same(a.u, b.u) && same(a.v, b.v) && same(a.eye, b.eye) &&
           std::memcmp(&a.half_u, &b.half_u, sizeof a.half_u) == 0 && std::memcmp(&a.half_v, &b.half_v, sizeof a.half_v) == 0 &&
           a.cells_u == b.cells_u && a.cells_v == b.cells_v;
}
constexpr size_t kKeptColumns = 4;
std::mutex kept_mutex;
std::vector<KeptColumns> kept;

}  // namespace

std::shared_ptr<const RayColumns> shared_ray_columns(const std::shared_ptr<const TapeTree>& T, const ColumnsKey& key, bool keep) {
    if (!T) return nullptr;
    if (keep) {
        const std::lock_guard<std::mutex> lock(kept_mutex);
        for (const KeptColumns& k : kept)
            if (k.tree.lock() == T && same_key(k.key, key)) return k.columns;
    }
    std::shared_ptr<const RayColumns> c = build_ray_columns(*T, key);
    if (keep && c) {
        const std::lock_guard<std::mutex> lock(kept_mutex);
        std::erase_if(kept, [](const KeptColumns& k) { return k.tree.expired(); });
        if (kept.size() >= kKeptColumns) kept.erase(kept.begin());
        kept.push_back(KeptColumns{T, key, c});
    }
    return c;
}

}  // namespace sdfc::cpu
