// Making the bricks: the interval-culled octree, sampling, waking neighbours, unpinching.
#include "runtime/mesh/bricks.hpp"

#include <tbb/parallel_for.h>

#include <cfloat>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "runtime/mesh/cube.hpp"

namespace sdfc::mesh::dc {

// ------------------------------------------------------------------ classify

// Whether the interval [lo, hi] of f over the box proves the meshed field max(f, box)
// positive (+1) or negative (-1) on all of it; 0 when it does not.
static int proved_sign(const Grid& g, Interval v, const glm::vec3& lo, const glm::vec3& hi) {
    if (glm::any(glm::lessThan(hi, g.lo)) || glm::any(glm::greaterThan(lo, g.hi)) || v.lo > 0.0f) return 1;
    if (v.hi < 0.0f && glm::all(glm::greaterThan(lo, g.lo)) && glm::all(glm::lessThan(hi, g.hi))) return -1;
    return 0;
}

// Every brick the intervals do not prove empty or full, sampled with its simplified tape
// as soon as the tape is made (only bricks with surface keep theirs).
std::vector<Sampled> classify(const Grid& g, const Program& p, tbb::enumerable_thread_specific<Scratch>& tls) {
    int levels = 0;
    while ((1 << levels) < std::max({g.bricks.x, g.bricks.y, g.bricks.z})) ++levels;
    std::vector<Region> frontier(1);
    frontier[0].level = levels;
    frontier[0].tape = Tape::from(p, 0);
    frontier[0].tape.mark_min_chains();  // a union's far shapes go against its nearest anywhere
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
            iv.prune_min_chains(r.tape, n);
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
                const glm::vec3 lo(bx[0][k], bx[2][k], bx[4][k]), hi(bx[1][k], bx[3][k], bx[5][k]);
                const Interval v = iv.result(k);
                if (proved_sign(g, std::isfinite(centre[k]) ? tighten_by_centre(v, centre[k], glm::length(hi - lo)) : v, lo, hi)) continue;
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

Tape brick_tape(const Grid& g, const Tape& full, glm::ivec3 at, Scratch& s) {
    float bx[6][kIvLanes];
    for (int a = 0; a < 3; ++a) bx[2 * a][0] = g.coord(a, at[a] * kB), bx[2 * a + 1][0] = g.coord(a, (at[a] + 1) * kB);
    IntervalEvaluator& iv = s.interval(full.num_regs, full.choices);
    iv.eval(full, bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], 1, g.time);
    iv.prune_min_chains(full, 1);
    simplify_batch(full, iv.choices(), iv.stride(), 1, s.bs, true);
    Tape t;
    t.assign(s.bs.code(0), s.bs.len[0], s.bs.out[0], s.bs.regs[0]);
    t.link();
    return t;
}

// ------------------------------------------------------------------ sample

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
static bool pinched(const Brick& b, int ci, int f) {
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

}  // namespace sdfc::mesh::dc
