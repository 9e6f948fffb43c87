// Dual contouring on a grid of 8^3-cell bricks.
//
//   classify  an octree over the bricks, 8 children at a time through the interval
//             evaluator with their parent's tape: a region proved outside (or inside, away
//             from the box's walls) is skipped; the others get the tape simplified for their
//             box, down to single bricks (as the renderer's tape tree does)
//   sample    each remaining brick's 9^3 corners through the batch VM with its own tape;
//             a brick whose surface reaches a skipped neighbour wakes that neighbour (the
//             proofs are sound, this makes the mesh's closure independent of them)
//   vertices  every sign-changing edge's crossing (regula falsi) and normal (central
//             differences); one vertex per patch of a cell (cube.hpp) where its crossings'
//             tangent planes meet (qef.hpp), kept inside the cell
//   faces     one quad per sign-changing edge, joining the vertices of the four cells
//             around it, split along the flatter diagonal
//
// The field meshed is max(f, box): the solid cut by the box, so the mesh is closed.
// Corner values are computed once per brick; a corner shared by two bricks gets the same
// float from both (simplified tapes compute exactly what the full program computes).
#include "runtime/mesh/mesh.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "runtime/eval/interval.hpp"
#include "runtime/eval/vm.hpp"
#include "runtime/mesh/cube.hpp"
#include "runtime/mesh/qef.hpp"

namespace sdfc::mesh {
namespace {

constexpr int kB = 8;                 // cells per brick side
constexpr int kC = kB + 1;            // corners per brick side
constexpr int kC3 = kC * kC * kC;
constexpr int kCells = kB * kB * kB;
constexpr int kRefine = 6;            // regula falsi steps per crossing

struct Grid {
    glm::dvec3 origin{0.0};
    double h = 1.0;
    glm::ivec3 cells{0}, bricks{0};
    glm::vec3 lo{0.0f}, hi{0.0f};  // the box
    float time = 0.0f;
    bool lipschitz = true;  // a distance bound (not a raw field): intervals may be tightened
    // Triangles counted as bricks are sampled (two per sign-changing edge a brick owns),
    // so the limit stops the work before the memory grows.
    std::atomic<size_t>* triangles = nullptr;
    size_t max_triangles = 0;
    float coord(int axis, int i) const { return static_cast<float>(origin[axis] + double(i) * h); }
    glm::vec3 corner(glm::ivec3 c) const { return {coord(0, c.x), coord(1, c.y), coord(2, c.z)}; }
    size_t brick_index(glm::ivec3 b) const { return (size_t(b.z) * size_t(bricks.y) + size_t(b.y)) * size_t(bricks.x) + size_t(b.x); }
    float box(float x, float y, float z) const {
        const glm::vec3 c = 0.5f * (lo + hi), e = 0.5f * (hi - lo);
        const glm::vec3 q = glm::abs(glm::vec3(x, y, z) - c) - e;
        return glm::length(glm::max(q, 0.0f)) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0f);
    }
};

struct Brick {
    glm::ivec3 at{0};
    Tape tape;
    float value[kC3];
    uint8_t config[kCells];
    uint8_t flipped[kCells] = {};  // ambiguous faces linked the other way (cube.hpp)
    uint32_t vbase[kCells];  // first vertex of each cell, within the brick
    std::vector<glm::vec3> verts;
    std::vector<glm::ivec3> cell_of;  // each vertex's cell (while placing them)
    std::vector<std::array<uint32_t, 3>> tris;
    uint32_t first_vertex = 0;
};

int corner_index(int x, int y, int z) { return (z * kC + y) * kC + x; }
int cell_index(int x, int y, int z) { return (z * kB + y) * kB + x; }

struct Scratch {
    BatchVM vm{64};
    std::unique_ptr<IntervalEvaluator> iv;
    uint32_t iv_regs = 0, iv_choices = 0;
    BatchScratch bs;
    std::vector<float> x, y, z, f;
    float value[kC3];
    IntervalEvaluator& interval(uint32_t regs, uint32_t choices) {
        if (!iv || regs > iv_regs || choices > iv_choices) {
            iv_regs = std::max(iv_regs, regs), iv_choices = std::max(iv_choices, choices);
            iv = std::make_unique<IntervalEvaluator>(iv_regs, iv_choices);
        }
        return *iv;
    }
    // The meshed field max(f, box) at the points in x, y, z, into f.
    void field(const Grid& g, const TapeView& t) {
        const size_t n = x.size();
        f.resize(n);
        for (size_t i = 0; i < n; i += kBatch) {
            const int m = static_cast<int>(std::min<size_t>(kBatch, n - i));
            vm.eval(t, x.data() + i, y.data() + i, z.data() + i, m, g.time);
            const float* r = vm.output(t);
            for (int j = 0; j < m; ++j) {
                const float b = g.box(x[i + j], y[i + j], z[i + j]);
                f[i + j] = r[j] < b ? b : r[j];  // NaN stays NaN: outside
            }
        }
    }
};

bool inside(float v) { return v < 0.0f; }

// ------------------------------------------------------------------ classify

struct Region {
    glm::ivec3 at{0};  // in bricks
    int level = 0;     // 2^level bricks per side
    Tape tape;
};

std::unique_ptr<Brick> sample(const Grid& g, Region& r, Scratch& s);

// A brick the intervals did not prove empty or full, sampled: null when it had no surface.
struct Sampled {
    glm::ivec3 at{0};
    std::unique_ptr<Brick> brick;
};

// Every brick the intervals do not prove empty or full, sampled with its simplified tape
// as soon as the tape is made (only bricks with surface keep theirs).
std::vector<Sampled> classify(const Grid& g, const Program& p, tbb::enumerable_thread_specific<Scratch>& tls) {
    int levels = 0;
    while ((1 << levels) < std::max({g.bricks.x, g.bricks.y, g.bricks.z})) ++levels;
    std::vector<Region> frontier(1);
    frontier[0].level = levels;
    frontier[0].tape = Tape::from(p, 0);
    frontier[0].tape.link();
    std::vector<Sampled> out;
    if (levels == 0) {
        out.push_back({frontier[0].at, sample(g, frontier[0], tls.local())});
        return out;
    }
    while (!frontier.empty()) {
        std::vector<std::vector<Region>> kids(frontier.size());
        std::vector<std::vector<Sampled>> leaves(frontier.size());
        tbb::parallel_for(size_t(0), frontier.size(), [&](size_t q) {
            Scratch& s = tls.local();
            Region& r = frontier[q];
            const int half = 1 << (r.level - 1);
            float bx[6][kIvLanes];
            glm::ivec3 child_at[8];
            int n = 0;
            for (int k = 0; k < 8; ++k) {
                const glm::ivec3 c = r.at + glm::ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1) * half;
                if (c.x >= g.bricks.x || c.y >= g.bricks.y || c.z >= g.bricks.z) continue;
                const glm::ivec3 e = glm::min(c + half, g.bricks);
                for (int a = 0; a < 3; ++a) {
                    bx[2 * a][n] = g.coord(a, c[a] * kB);
                    bx[2 * a + 1][n] = g.coord(a, e[a] * kB);
                }
                child_at[n++] = c;
            }
            IntervalEvaluator& iv = s.interval(r.tape.num_regs, r.tape.choices);
            iv.eval(r.tape, bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], n, g.time);
            float centre[8];
            std::fill_n(centre, 8, NAN);
            if (g.lipschitz) {
                s.x.resize(size_t(n)), s.y.resize(size_t(n)), s.z.resize(size_t(n));
                for (int k = 0; k < n; ++k) {
                    s.x[size_t(k)] = 0.5f * (bx[0][k] + bx[1][k]);
                    s.y[size_t(k)] = 0.5f * (bx[2][k] + bx[3][k]);
                    s.z[size_t(k)] = 0.5f * (bx[4][k] + bx[5][k]);
                }
                const TapeView t = r.tape.view();
                s.vm.eval(t, s.x.data(), s.y.data(), s.z.data(), n, g.time);
                std::copy_n(s.vm.output(t), n, centre);
            }
            uint64_t lanes = 0;
            for (int k = 0; k < n; ++k) {
                Interval v = iv.result(k);
                const glm::vec3 lo(bx[0][k], bx[2][k], bx[4][k]), hi(bx[1][k], bx[3][k], bx[5][k]);
                if (std::isfinite(centre[k])) {  // a 1-Lipschitz bound is within |p - c| of its centre value
                    const float rad = 0.5f * glm::length(hi - lo) * (1.0f + 1e-5f) + 1e-6f * (1.0f + std::fabs(centre[k]));
                    if (!(v.lo >= centre[k] - rad)) v.lo = centre[k] - rad;
                    if (!(v.hi <= centre[k] + rad)) v.hi = centre[k] + rad;
                }
                const bool out_of_box = glm::any(glm::lessThan(hi, g.lo)) || glm::any(glm::greaterThan(lo, g.hi));
                const bool in_box = glm::all(glm::greaterThan(lo, g.lo)) && glm::all(glm::lessThan(hi, g.hi));
                if (out_of_box || v.lo > 0.0f || (v.hi < 0.0f && in_box)) continue;
                lanes |= uint64_t(1) << k;
            }
            if (!lanes) return;
            simplify_batch(r.tape, iv.choices(), iv.stride(), lanes, s.bs, true);
            for (int k = 0; k < n; ++k) {
                if (!((lanes >> k) & 1)) continue;
                Region c;
                c.at = child_at[k];
                c.level = r.level - 1;
                c.tape.assign(s.bs.code(k), s.bs.len[size_t(k)], s.bs.out[size_t(k)], s.bs.regs[size_t(k)]);
                c.tape.link();
                if (c.level == 0) leaves[q].push_back({c.at, sample(g, c, s)});
                else kids[q].push_back(std::move(c));
            }
        });
        std::vector<Region> next;
        for (auto& v : kids)
            for (auto& c : v) next.push_back(std::move(c));
        for (auto& v : leaves)
            for (auto& l : v) out.push_back(std::move(l));
        frontier = std::move(next);
    }
    return out;
}

// ------------------------------------------------------------------ sample

// The cells around each sign-changing edge of b (offsets -1 and 0 in the other two axes).
template <typename F>
void for_each_crossing(const Brick& b, F&& f) {
    for (int a = 0; a < 3; ++a) {
        const glm::ivec3 step(a == 0, a == 1, a == 2);
        for (int z = 0; z < kC - step.z; ++z)
            for (int y = 0; y < kC - step.y; ++y)
                for (int x = 0; x < kC - step.x; ++x) {
                    const bool in0 = inside(b.value[corner_index(x, y, z)]);
                    const bool in1 = inside(b.value[corner_index(x + step.x, y + step.y, z + step.z)]);
                    if (in0 != in1) f(a, glm::ivec3(x, y, z), in0);
                }
    }
}

// Whether the interval [lo, hi] of f over the box proves the meshed field max(f, box)
// positive (+1) or negative (-1) on all of it; 0 when it does not.
int proved_sign(const Grid& g, Interval v, const glm::vec3& lo, const glm::vec3& hi) {
    if (glm::any(glm::lessThan(hi, g.lo)) || glm::any(glm::greaterThan(lo, g.hi)) || v.lo > 0.0f) return 1;
    if (v.hi < 0.0f && glm::all(glm::greaterThan(lo, g.lo)) && glm::all(glm::lessThan(hi, g.hi))) return -1;
    return 0;
}

// The brick's corners. Its 64 blocks of 2^3 cells are interval-evaluated first: a block
// proved outside or inside gives its corners a sign (+-FLT_MAX) without evaluating them;
// the corners of the others are evaluated. The proofs hold for every float the VM computes
// in the box, so a corner shared with another block or brick gets the same sign from all.
// Null when every corner has the same sign: no surface, nothing to keep.
std::unique_ptr<Brick> sample(const Grid& g, Region& r, Scratch& s) {
    constexpr int kSub = 2, kSubs = kB / kSub;  // 4^3 = 64 blocks: one interval batch
    static_assert(kSubs * kSubs * kSubs == kIvLanes);
    float bx[6][kIvLanes];
    for (int k = 0; k < kIvLanes; ++k) {
        const glm::ivec3 c = r.at * kB + glm::ivec3(k % kSubs, k / kSubs % kSubs, k / (kSubs * kSubs)) * kSub;
        for (int a = 0; a < 3; ++a) bx[2 * a][k] = g.coord(a, c[a]), bx[2 * a + 1][k] = g.coord(a, c[a] + kSub);
    }
    if (!r.tape.linked) r.tape.link();
    IntervalEvaluator& iv = s.interval(r.tape.num_regs, r.tape.choices);
    iv.eval(r.tape, bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], kIvLanes, g.time);
    bool need[kC3] = {};
    float* value = s.value;
    for (int k = 0; k < kIvLanes; ++k) {
        const glm::ivec3 o = glm::ivec3(k % kSubs, k / kSubs % kSubs, k / (kSubs * kSubs)) * kSub;
        const int sign = proved_sign(g, iv.result(k), {bx[0][k], bx[2][k], bx[4][k]}, {bx[1][k], bx[3][k], bx[5][k]});
        for (int z = 0; z <= kSub; ++z)
            for (int y = 0; y <= kSub; ++y)
                for (int x = 0; x <= kSub; ++x) {
                    const int ci = corner_index(o.x + x, o.y + y, o.z + z);
                    if (sign == 0) need[ci] = true;
                    else value[ci] = sign > 0 ? FLT_MAX : -FLT_MAX;
                }
    }
    s.x.clear(), s.y.clear(), s.z.clear();
    for (int z = 0; z < kC; ++z)
        for (int y = 0; y < kC; ++y)
            for (int x = 0; x < kC; ++x) {
                if (!need[corner_index(x, y, z)]) continue;
                const glm::vec3 p = g.corner(r.at * kB + glm::ivec3(x, y, z));
                s.x.push_back(p.x), s.y.push_back(p.y), s.z.push_back(p.z);
            }
    s.field(g, r.tape.view());
    size_t j = 0, inside_corners = 0;
    for (int ci = 0; ci < kC3; ++ci) {
        if (need[ci]) value[ci] = s.f[j++];
        inside_corners += inside(value[ci]);
    }
    if (inside_corners == 0 || inside_corners == size_t(kC3)) return nullptr;
    auto bp = std::make_unique<Brick>();
    Brick& b = *bp;
    b.at = r.at;
    b.tape = std::move(r.tape);
    std::copy_n(value, kC3, b.value);
    for (int z = 0; z < kB; ++z)
        for (int y = 0; y < kB; ++y)
            for (int x = 0; x < kB; ++x) {
                uint8_t c = 0;
                for (int k = 0; k < 8; ++k)
                    c |= uint8_t(inside(b.value[corner_index(x + (k & 1), y + ((k >> 1) & 1), z + ((k >> 2) & 1))]) << k);
                b.config[cell_index(x, y, z)] = c;
            }
    size_t quads = 0;
    for_each_crossing(b, [&](int, glm::ivec3 c, bool) { quads += c.x < kB && c.y < kB && c.z < kB; });
    const size_t total = g.triangles->fetch_add(2 * quads) + 2 * quads;
    if (total > g.max_triangles)
        throw std::runtime_error(
            fmt::format("the mesh's triangles are over the limit of {} (raise it with --max-triangles)", g.max_triangles));
    return bp;
}

// Bricks the surface of `b` reaches that are not in the set (marked in `want`).
void neighbours_needed(const Grid& g, const Brick& b, const std::vector<int32_t>& map, std::vector<uint8_t>& want) {
    for_each_crossing(b, [&](int a, glm::ivec3 c, bool) {
        const int u = (a + 1) % 3, v = (a + 2) % 3;
        for (int k = 0; k < 4; ++k) {
            glm::ivec3 cell = b.at * kB + c;
            cell[u] -= (k & 1), cell[v] -= (k >> 1);
            if (glm::any(glm::lessThan(cell, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(cell, g.cells))) continue;
            const size_t bi = g.brick_index(cell / kB);
            if (map[bi] == -1) want[bi] = 1;  // never sampled
        }
    });
}

// ------------------------------------------------------------------ pinches

// Whether the cell's face f is ambiguous and one patch runs through all four of its edges.
bool pinched(const Brick& b, int ci, int f) {
    const uint8_t cfg = b.config[ci];
    const Patches& pt = patches(cfg, b.flipped[ci]);
    const std::array<int, 4> fe = face_edges(f);
    for (int e : fe)
        if (pt.of_edge[e] < 0 || pt.of_edge[e] != pt.of_edge[fe[0]]) return false;
    return true;
}

// Flips every face pinched on both sides (cube.hpp), until none is; the flips found in
// parallel, applied after.
void unpinch(const Grid& g, std::vector<std::unique_ptr<Brick>>& bricks, const std::vector<int32_t>& map) {
    struct Flip {
        uint32_t brick;
        uint16_t cell;
        uint8_t face;
    };
    for (int pass = 0; pass < 8; ++pass) {
        std::vector<std::vector<Flip>> found(bricks.size());
        tbb::parallel_for(size_t(0), bricks.size(), [&](size_t i) {
            const Brick& b = *bricks[i];
            for (int ci = 0; ci < kCells; ++ci) {
                const uint8_t cfg = b.config[ci];
                if (cfg == 0 || cfg == 255) continue;
                const glm::ivec3 l(ci % kB, ci / kB % kB, ci / (kB * kB));
                for (int a = 0; a < 3; ++a) {
                    if (!pinched(b, ci, 2 * a + 1)) continue;
                    glm::ivec3 cell = b.at * kB + l;
                    cell[a] += 1;
                    if (cell[a] >= g.cells[a]) continue;
                    const glm::ivec3 bat = cell / kB;
                    const int32_t bi = map[g.brick_index(bat)];
                    if (bi < 0) continue;
                    const glm::ivec3 nl = cell - bat * kB;
                    const int nci = cell_index(nl.x, nl.y, nl.z);
                    if (!pinched(*bricks[size_t(bi)], nci, 2 * a)) continue;
                    found[i].push_back({uint32_t(i), uint16_t(ci), uint8_t(2 * a + 1)});
                    found[i].push_back({uint32_t(bi), uint16_t(nci), uint8_t(2 * a)});
                }
            }
        });
        size_t n = 0;
        for (auto& v : found)
            for (const Flip& f : v) bricks[f.brick]->flipped[f.cell] ^= uint8_t(1u << f.face), ++n;
        if (n == 0) return;
    }
}

// ------------------------------------------------------------------ vertices

// Vertices the planes left off the surface (a cell that holds a crease but not the corner
// its planes meet at, or normals blurred by a nearby crease) are moved onto it: Newton
// steps along the gradient, kept in the cell. Those within 1/25 of a cell stay (on a curved
// surface the planes meet a little outside it, which makes up for the flat triangles).
void settle_vertices(const Grid& g, Brick& b, Scratch& s) {
    const float h = static_cast<float>(g.h), tol = 0.04f * h, d = std::max(1e-3f * h, 1e-6f);
    const TapeView tape = b.tape.view();
    std::vector<uint32_t> todo(b.verts.size());
    for (uint32_t i = 0; i < todo.size(); ++i) todo[i] = i;
    for (int step = 0; step < 3 && !todo.empty(); ++step) {
        s.x.resize(7 * todo.size()), s.y.resize(7 * todo.size()), s.z.resize(7 * todo.size());
        for (size_t j = 0; j < todo.size(); ++j)
            for (int k = 0; k < 7; ++k) {
                glm::vec3 p = b.verts[todo[j]];
                if (k > 0) p[(k - 1) / 2] += (k & 1) ? d : -d;
                s.x[7 * j + size_t(k)] = p.x, s.y[7 * j + size_t(k)] = p.y, s.z[7 * j + size_t(k)] = p.z;
            }
        s.field(g, tape);
        size_t kept = 0;
        for (size_t j = 0; j < todo.size(); ++j) {
            const float* f = s.f.data() + 7 * j;
            if (!(std::fabs(f[0]) > tol)) continue;  // on the surface (or NaN: left alone)
            const glm::vec3 grad = glm::vec3(f[1] - f[2], f[3] - f[4], f[5] - f[6]) / (2.0f * d);
            const float g2 = glm::dot(grad, grad);
            if (!(g2 > 1e-12f) || !std::isfinite(g2)) continue;
            const glm::ivec3 cell = b.cell_of[todo[j]];
            glm::vec3& v = b.verts[todo[j]];
            v = glm::clamp(v - grad * (f[0] / g2), g.corner(cell), g.corner(cell + 1));
            todo[kept++] = todo[j];
        }
        todo.resize(kept);
    }
}

void place_vertices(const Grid& g, Brick& b, Scratch& s) {
    // Every sign-changing edge of the brick's lattice: slot a * kC3 + lower corner.
    struct Crossing {
        int slot;
        glm::vec3 p0;
        int axis;
        float t0, t1, f0, f1;
    };
    std::vector<Crossing> xs;
    for_each_crossing(b, [&](int a, glm::ivec3 c, bool) {
        const glm::ivec3 step(a == 0, a == 1, a == 2);
        const float f0 = b.value[corner_index(c.x, c.y, c.z)], f1 = b.value[corner_index(c.x + step.x, c.y + step.y, c.z + step.z)];
        xs.push_back({a * kC3 + corner_index(c.x, c.y, c.z), g.corner(b.at * kB + c), a, 0.0f, 1.0f, f0, f1});
    });
    const float h = static_cast<float>(g.h);
    auto point = [&](const Crossing& x, float t) {
        glm::vec3 p = x.p0;
        p[x.axis] += t * h;
        return p;
    };
    auto guess = [](const Crossing& x) {
        if (!std::isfinite(x.f0) || !std::isfinite(x.f1) || x.f0 == x.f1) return 0.5f * (x.t0 + x.t1);
        const float t = x.t0 + (x.t1 - x.t0) * x.f0 / (x.f0 - x.f1);
        return std::clamp(t, x.t0 + 0.01f * (x.t1 - x.t0), x.t1 - 0.01f * (x.t1 - x.t0));
    };
    const TapeView tape = b.tape.view();
    for (int it = 0; it < kRefine && !xs.empty(); ++it) {
        s.x.resize(xs.size()), s.y.resize(xs.size()), s.z.resize(xs.size());
        std::vector<float> ts(xs.size());
        for (size_t i = 0; i < xs.size(); ++i) {
            ts[i] = guess(xs[i]);
            const glm::vec3 p = point(xs[i], ts[i]);
            s.x[i] = p.x, s.y[i] = p.y, s.z[i] = p.z;
        }
        s.field(g, tape);
        for (size_t i = 0; i < xs.size(); ++i) {  // Illinois: halve the stale end's value
            Crossing& x = xs[i];
            const float v = s.f[i];
            if (inside(v) == inside(x.f0)) {
                x.t0 = ts[i], x.f0 = v;
                x.f1 *= 0.5f;
            } else {
                x.t1 = ts[i], x.f1 = v;
                x.f0 *= 0.5f;
            }
        }
    }
    // Crossings and normals (central differences of the meshed field).
    const float d = std::max(1e-3f * h, 1e-6f);
    std::vector<glm::vec3> at(xs.size());
    s.x.resize(6 * xs.size()), s.y.resize(6 * xs.size()), s.z.resize(6 * xs.size());
    for (size_t i = 0; i < xs.size(); ++i) {
        at[i] = point(xs[i], guess(xs[i]));
        for (int k = 0; k < 6; ++k) {
            glm::vec3 p = at[i];
            p[k / 2] += (k & 1) ? -d : d;
            s.x[6 * i + size_t(k)] = p.x, s.y[6 * i + size_t(k)] = p.y, s.z[6 * i + size_t(k)] = p.z;
        }
    }
    s.field(g, tape);
    std::vector<int> slot_of(3 * kC3, -1);
    std::vector<glm::vec3> normal(xs.size());
    for (size_t i = 0; i < xs.size(); ++i) {
        const float* f = s.f.data() + 6 * i;
        glm::vec3 n(f[0] - f[1], f[2] - f[3], f[4] - f[5]);
        const float len = glm::length(n);
        if (std::isfinite(len) && len > 0.0f) {
            n /= len;
        } else {  // no gradient: the edge's own direction, pointing outwards
            n = glm::vec3(0.0f);
            n[xs[i].axis] = inside(b.value[xs[i].slot % kC3]) ? 1.0f : -1.0f;
        }
        normal[i] = n;
        slot_of[size_t(xs[i].slot)] = static_cast<int>(i);
    }
    b.verts.clear();
    b.cell_of.clear();
    for (int z = 0; z < kB; ++z)
        for (int y = 0; y < kB; ++y)
            for (int x = 0; x < kB; ++x) {
                const int ci = cell_index(x, y, z);
                b.vbase[ci] = static_cast<uint32_t>(b.verts.size());
                const uint8_t cfg = b.config[ci];
                if (cfg == 0 || cfg == 255) continue;
                const Patches& pt = patches(cfg, b.flipped[ci]);
                const glm::ivec3 cell = b.at * kB + glm::ivec3(x, y, z);
                const glm::vec3 lo = g.corner(cell), hi = g.corner(cell + 1);
                for (int q = 0; q < pt.count; ++q) {
                    Qef qef;
                    for (int e = 0; e < 12; ++e) {
                        if (pt.of_edge[e] != q) continue;
                        const int c0 = edge_corners(e)[0];
                        const int slot = (e / 4) * kC3 + corner_index(x + (c0 & 1), y + ((c0 >> 1) & 1), z + ((c0 >> 2) & 1));
                        const int i = slot_of[size_t(slot)];
                        if (i >= 0) qef.add(at[size_t(i)], normal[size_t(i)]);
                    }
                    b.verts.push_back(glm::clamp(glm::vec3(qef.solve_in(glm::dvec3(lo), glm::dvec3(hi))), lo, hi));
                    b.cell_of.push_back(cell);
                }
            }
    settle_vertices(g, b, s);
}

// ------------------------------------------------------------------ faces

void make_faces(const Grid& g, Brick& b, const std::vector<int32_t>& map, const std::vector<std::unique_ptr<Brick>>& bricks) {
    b.tris.clear();
    for_each_crossing(b, [&](int a, glm::ivec3 c, bool lower_inside) {
        if (c.x >= kB || c.y >= kB || c.z >= kB) return;  // owned by the next brick
        const int u = (a + 1) % 3, v = (a + 2) % 3;
        const int lo_axis = std::min(u, v), hi_axis = std::max(u, v);
        static constexpr int du[4] = {1, 0, 0, 1}, dv[4] = {1, 1, 0, 0};  // -1 offsets of the quad's cells, in order
        uint32_t q[4];
        glm::vec3 pos[4];
        for (int k = 0; k < 4; ++k) {
            glm::ivec3 cell = b.at * kB + c;
            cell[u] -= du[k], cell[v] -= dv[k];
            const glm::ivec3 bat = cell / kB;
            const int32_t bi = map[g.brick_index(bat)];
            if (bi < 0) throw std::logic_error("mesh: a crossing's cell is in no sampled brick");
            const Brick& nb = *bricks[size_t(bi)];
            const glm::ivec3 l = cell - bat * kB;
            const int ci = cell_index(l.x, l.y, l.z);
            // The edge within that cell: its coordinates on u and v are the offsets.
            int bits[3] = {0, 0, 0};
            bits[u] = du[k], bits[v] = dv[k];
            const int e = a * 4 + bits[lo_axis] + 2 * bits[hi_axis];
            const int patch = patches(nb.config[ci], nb.flipped[ci]).of_edge[e];
            if (patch < 0) throw std::logic_error("mesh: a crossing's cell has no patch for it");
            q[k] = nb.first_vertex + nb.vbase[ci] + uint32_t(patch);
            pos[k] = nb.verts[nb.vbase[ci] + uint32_t(patch)];
        }
        if (!lower_inside) std::swap(q[1], q[3]), std::swap(pos[1], pos[3]);
        // Split along the diagonal whose triangles fold least.
        auto fold = [&](int i) {
            const glm::vec3 n0 = glm::cross(pos[(i + 1) % 4] - pos[i], pos[(i + 2) % 4] - pos[i]);
            const glm::vec3 n1 = glm::cross(pos[(i + 2) % 4] - pos[i], pos[(i + 3) % 4] - pos[i]);
            const float l = glm::length(n0) * glm::length(n1);
            return l > 0.0f ? glm::dot(n0, n1) / l : -2.0f;
        };
        const int i = fold(0) >= fold(1) ? 0 : 1;
        b.tris.push_back({q[i], q[(i + 1) % 4], q[(i + 2) % 4]});
        b.tris.push_back({q[i], q[(i + 2) % 4], q[(i + 3) % 4]});
    });
}

}  // namespace

double grid_cells(const MeshOptions& o) {
    const glm::vec3 ext = o.hi - o.lo;
    const double h = std::max({ext.x, ext.y, ext.z}) / double(o.resolution);
    double n = 1.0;
    for (int a = 0; a < 3; ++a) n *= std::ceil((std::ceil(ext[a] / h - 1e-4) + 2.0) / kB) * kB;
    return n;
}

bool default_box(const CompiledScene& scene, glm::vec3& lo, glm::vec3& hi) {
    if (scene.raw_field) {
        lo = glm::vec3(-1.0f), hi = glm::vec3(1.0f);
        return true;
    }
    // Floor planes make the bounds infinite: the box around the rest (solid_bounds).
    const Bounds& b = scene.bounds.finite() ? scene.bounds : scene.solid_bounds;
    if (!b.finite() || !(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) return false;
    const glm::vec3 ext = b.hi - b.lo;
    const float m = 0.02f * std::max({ext.x, ext.y, ext.z, 1e-3f});
    lo = b.lo - m, hi = b.hi + m;
    return true;
}

Mesh mesh_scene(const CompiledScene& scene, const MeshOptions& o, MeshStats* stats) {
    Grid g;
    std::atomic<size_t> triangles{0};
    g.triangles = &triangles, g.max_triangles = o.max_triangles;
    g.lo = o.lo, g.hi = o.hi, g.time = o.time;
    g.lipschitz = !scene.raw_field;
    const glm::vec3 ext = o.hi - o.lo;
    g.h = std::max({ext.x, ext.y, ext.z}) / double(o.resolution);
    g.origin = glm::dvec3(o.lo) - g.h;  // a cell of padding outside the box on every side
    for (int a = 0; a < 3; ++a) {
        g.bricks[a] = static_cast<int>(std::ceil((std::ceil(ext[a] / g.h - 1e-4) + 2.0) / kB));
        g.cells[a] = g.bricks[a] * kB;
    }
    Mesh m;
    if (scene.distance.outputs.empty()) return m;
    tbb::enumerable_thread_specific<Scratch> tls;

    // map: the brick's index in `bricks`, kUnsampled, or kUniform (sampled: no surface).
    constexpr int32_t kUnsampled = -1, kUniform = -2;
    auto progress = [&](double f) {
        if (o.progress) o.progress(f);
    };
    std::vector<Sampled> got = classify(g, scene.distance, tls);
    progress(0.5);
    const size_t classified = got.size();
    const size_t nbricks = size_t(g.bricks.x) * size_t(g.bricks.y) * size_t(g.bricks.z);
    std::vector<int32_t> map(nbricks, kUnsampled);
    std::vector<std::unique_ptr<Brick>> bricks;
    // Then wake the skipped neighbours the surface reaches, until none is left.
    const Tape full = [&] {
        Tape t = Tape::from(scene.distance, 0);
        t.link();
        return t;
    }();
    std::vector<uint8_t> want(nbricks, 0);
    size_t sampled = 0;
    while (!got.empty()) {
        sampled += got.size();
        const size_t first = bricks.size();
        for (Sampled& x : got) {
            const size_t bi = g.brick_index(x.at);
            if (!x.brick) {
                map[bi] = kUniform;
                continue;
            }
            map[bi] = static_cast<int32_t>(bricks.size());
            bricks.push_back(std::move(x.brick));
        }
        for (size_t i = first; i < bricks.size(); ++i) neighbours_needed(g, *bricks[i], map, want);
        std::vector<Region> todo;
        for (size_t bi = 0; bi < nbricks; ++bi) {
            if (!want[bi]) continue;
            want[bi] = 0;
            Region r;
            r.at = glm::ivec3(int(bi % size_t(g.bricks.x)), int(bi / size_t(g.bricks.x) % size_t(g.bricks.y)),
                              int(bi / (size_t(g.bricks.x) * size_t(g.bricks.y))));
            r.tape = full;
            todo.push_back(std::move(r));
        }
        got.clear();
        got.resize(todo.size());
        tbb::parallel_for(size_t(0), todo.size(), [&](size_t i) { got[i] = {todo[i].at, sample(g, todo[i], tls.local())}; });
    }
    progress(0.6);
    unpinch(g, bricks, map);
    tbb::parallel_for(size_t(0), bricks.size(), [&](size_t i) { place_vertices(g, *bricks[i], tls.local()); });
    progress(0.85);
    size_t nverts = 0;
    for (auto& b : bricks) {
        b->first_vertex = static_cast<uint32_t>(nverts);
        nverts += b->verts.size();
        if (nverts > 3 * o.max_triangles) break;  // checked below, with the triangles
    }
    if (nverts >= 0xFFFFFFFFu || nverts / 2 > o.max_triangles)
        throw std::runtime_error(fmt::format("the mesh would have about {} triangles, over the limit of {} (raise it with --max-triangles)",
                                             2 * nverts, o.max_triangles));
    tbb::parallel_for(size_t(0), bricks.size(), [&](size_t i) { make_faces(g, *bricks[i], map, bricks); });
    progress(0.95);
    size_t ntris = 0;
    for (auto& b : bricks) ntris += b->tris.size();
    if (ntris > o.max_triangles)
        throw std::runtime_error(fmt::format("the mesh would have {} triangles, over the limit of {} (raise it with --max-triangles)",
                                             ntris, o.max_triangles));
    m.positions.reserve(nverts);
    m.triangles.reserve(ntris);
    for (auto& b : bricks) {
        m.positions.insert(m.positions.end(), b->verts.begin(), b->verts.end());
        m.triangles.insert(m.triangles.end(), b->tris.begin(), b->tris.end());
    }
    if (o.colors && scene.shading.outputs.size() >= 1 + kMatChannels) {
        m.colors.resize(m.positions.size());
        tbb::parallel_for(size_t(0), (m.positions.size() + kBatch - 1) / kBatch, [&](size_t blk) {
            Scratch& s = tls.local();
            const size_t i0 = blk * kBatch, n = std::min<size_t>(kBatch, m.positions.size() - i0);
            float x[kBatch], y[kBatch], z[kBatch];
            for (size_t j = 0; j < n; ++j) x[j] = m.positions[i0 + j].x, y[j] = m.positions[i0 + j].y, z[j] = m.positions[i0 + j].z;
            const TapeView t = scene.shading.view();
            s.vm.eval(t, x, y, z, int(n), g.time);
            for (int c = 0; c < 3; ++c) {
                const float* r = s.vm.output(t, uint32_t(1 + kMatR + c));
                for (size_t j = 0; j < n; ++j) m.colors[i0 + j][c] = std::isfinite(r[j]) ? std::clamp(r[j], 0.0f, 1.0f) : 0.0f;
            }
        });
    }
    if (stats) {
        stats->cells = g.cells;
        stats->bricks = nbricks;
        stats->active_bricks = classified;
        stats->rescued_bricks = sampled - classified;
        stats->vertices = m.positions.size();
        stats->triangles = m.triangles.size();
    }
    return m;
}

}  // namespace sdfc::mesh
