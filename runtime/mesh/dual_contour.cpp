// Dual contouring on a grid of 8^3-cell bricks.
//
//   classify  an octree over the bricks, 8 children at a time through the interval
//             evaluator with their parent's tape: a region proved outside (or inside, away
//             from the box's walls) is skipped; the others get the tape simplified for their
//             box, down to single bricks (as the renderer's tape tree does)
//   sample    each remaining brick's 9^3 corners through the batch VM with its own tape;
//             a brick whose surface reaches a skipped neighbour wakes that neighbour (the
//             proofs are sound, this makes the mesh's closure independent of them)
//   vertices  every sign-changing edge's crossing (regula falsi) and normal (the forward-
//             mode gradient evaluator, runtime/eval/gradient.hpp); one vertex per patch of a cell (cube.hpp) where its crossings'
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
#include <unordered_map>

#include "runtime/mesh/bricks.hpp"
#include "runtime/mesh/cube.hpp"
#include "runtime/mesh/qef.hpp"
#include "runtime/mesh/simplify.hpp"

namespace sdfc::mesh {
namespace {

using namespace dc;

constexpr double kContouringShare = 0.25;  // of the progress bar, when the mesh is simplified after

// ------------------------------------------------------------------ vertices

// A cell's box for its vertices, a hair inside its faces: two cells whose vertices both meet
// their shared face (a sharp edge or a flat face lying on a grid plane) would otherwise put
// them at one point, and the quads between them would have no area (an STL, which has no
// indices, then has edges that are not shared by two triangles). Not at the meshed box's
// walls: nothing lies beyond them, and a cut's vertices stay on them.
void vertex_box(const Grid& g, glm::ivec3 cell, glm::vec3& lo, glm::vec3& hi) {
    lo = g.corner(cell), hi = g.corner(cell + 1);
    for (int k = 0; k < 3; ++k) {
        const float ulp = FLT_EPSILON * std::max(std::fabs(lo[k]), std::fabs(hi[k]));
        const float m = std::max(1e-3f * (hi[k] - lo[k]), 8.0f * ulp);
        if (!(hi[k] - lo[k] > 4.0f * m)) continue;
        if (lo[k] > g.lo[k]) lo[k] += m;
        if (hi[k] < g.hi[k]) hi[k] -= m;
    }
    lo = glm::max(lo, g.lo), hi = glm::min(hi, g.hi);  // (a cell may reach out of a thin box)
}

// Vertices the planes left off the surface (a cell that holds a crease but not the corner
// its planes meet at, or normals blurred by a nearby crease) are moved onto it: Newton
// steps along the gradient, kept in the cell. Those within 1/25 of a cell stay (on a curved
// surface the planes meet a little outside it, which makes up for the flat triangles).
void settle_vertices(const Grid& g, Brick& b, Scratch& s) {
    const float tol = 0.04f * static_cast<float>(g.h);
    const TapeView tape = b.tape.view();
    std::vector<uint32_t> todo(b.verts.size());
    for (uint32_t i = 0; i < todo.size(); ++i) todo[i] = i;
    for (int step = 0; step < 3 && !todo.empty(); ++step) {
        s.x.resize(todo.size()), s.y.resize(todo.size()), s.z.resize(todo.size());
        for (size_t j = 0; j < todo.size(); ++j) {
            const glm::vec3 p = b.verts[todo[j]];
            s.x[j] = p.x, s.y[j] = p.y, s.z[j] = p.z;
        }
        s.field_gradient(g, tape);
        size_t kept = 0;
        for (size_t j = 0; j < todo.size(); ++j) {
            const Dual& f = s.fg[j];
            if (!(std::fabs(f.v) > tol)) continue;  // on the surface (or NaN: left alone)
            const glm::vec3 grad(f.dx, f.dy, f.dz);
            const float g2 = glm::dot(grad, grad);
            if (!(g2 > 1e-12f) || !std::isfinite(g2)) continue;
            glm::vec3 lo, hi;
            vertex_box(g, b.cell_of[todo[j]], lo, hi);
            glm::vec3& v = b.verts[todo[j]];
            v = glm::clamp(v - grad * (f.v / g2), lo, hi);
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
    // Crossings and normals (the gradient evaluator's, of the meshed field).
    std::vector<glm::vec3> at(xs.size());
    s.x.resize(xs.size()), s.y.resize(xs.size()), s.z.resize(xs.size());
    for (size_t i = 0; i < xs.size(); ++i) {
        at[i] = point(xs[i], guess(xs[i]));
        s.x[i] = at[i].x, s.y[i] = at[i].y, s.z[i] = at[i].z;
    }
    s.field_gradient(g, tape);
    std::vector<int> slot_of(3 * kC3, -1);
    std::vector<glm::vec3> normal(xs.size());
    for (size_t i = 0; i < xs.size(); ++i) {
        glm::vec3 n(s.fg[i].dx, s.fg[i].dy, s.fg[i].dz);
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
    std::vector<uint32_t> shared;  // the first vertex of each cell with several
    std::vector<glm::vec3> mass;   // per vertex: the middle of its sheet's crossings
    for (int z = 0; z < kB; ++z)
        for (int y = 0; y < kB; ++y)
            for (int x = 0; x < kB; ++x) {
                const int ci = cell_index(x, y, z);
                b.vbase[ci] = static_cast<uint32_t>(b.verts.size());
                const uint8_t cfg = b.config[ci];
                if (cfg == 0 || cfg == 255) continue;
                const Patches& pt = patches(cfg, b.flipped[ci]);
                const glm::ivec3 cell = b.at * kB + glm::ivec3(x, y, z);
                glm::vec3 lo, hi;
                vertex_box(g, cell, lo, hi);
                if (pt.count > 1) shared.push_back(b.vbase[ci]);
                for (int q = 0; q < pt.count; ++q) {
                    Qef qef;
                    glm::vec3 sum(0.0f);
                    int n = 0;
                    for (int e = 0; e < 12; ++e) {
                        if (pt.of_edge[e] != q) continue;
                        const int c0 = edge_corners(e)[0];
                        const int slot = (e / 4) * kC3 + corner_index(x + (c0 & 1), y + ((c0 >> 1) & 1), z + ((c0 >> 2) & 1));
                        const int i = slot_of[size_t(slot)];
                        if (i >= 0) qef.add(at[size_t(i)], normal[size_t(i)]), sum += at[size_t(i)], ++n;
                    }
                    b.verts.push_back(glm::vec3(qef.solve_in(glm::dvec3(lo), glm::dvec3(hi))));
                    b.cell_of.push_back(cell);
                    mass.push_back(n > 0 ? sum / float(n) : b.verts.back());
                }
            }
    settle_vertices(g, b, s);
    // A cell with two sheets (or more) whose vertices met (both planes' corner clamped to one
    // point of the cell's box, or settled onto one point) would pinch the mesh there: an STL
    // has no indices, so a reader merges them. Each moves a quarter of the way to the middle
    // of its own sheet's crossings.
    for (const uint32_t first : shared) {
        const glm::ivec3 cell = b.cell_of[first];
        uint32_t end = first;
        while (end < b.verts.size() && b.cell_of[end] == cell) ++end;
        glm::vec3 lo, hi;
        vertex_box(g, cell, lo, hi);
        for (uint32_t i = first; i < end; ++i)
            for (uint32_t j = i + 1; j < end; ++j)
                if (glm::distance(b.verts[i], b.verts[j]) < 1e-3f * h)
                    for (const uint32_t k : {i, j}) b.verts[k] = glm::clamp(glm::mix(b.verts[k], mass[k], 0.25f), lo, hi);
    }
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

// The grid over the box: cubic cells, `resolution` along its longest side, a cell of
// padding outside it on every side, rounded up to whole bricks.
Grid grid_for(const MeshOptions& o) {
    Grid g;
    g.lo = o.lo, g.hi = o.hi, g.time = o.time;
    const glm::vec3 ext = o.hi - o.lo;
    g.h = std::max({ext.x, ext.y, ext.z}) / double(o.resolution);
    g.origin = glm::dvec3(o.lo) - g.h;
    for (int a = 0; a < 3; ++a) {
        g.bricks[a] = static_cast<int>(std::ceil((std::ceil(ext[a] / g.h - 1e-4) + 2.0) / kB));
        g.cells[a] = g.bricks[a] * kB;
    }
    return g;
}

}  // namespace

double grid_cells(const MeshOptions& o) {
    const Grid g = grid_for(o);
    return double(g.cells.x) * double(g.cells.y) * double(g.cells.z);
}

Mesh mesh_scene(const CompiledScene& scene, const MeshOptions& o, MeshStats* stats) {
    Grid g = grid_for(o);
    std::atomic<size_t> triangles{0};
    g.triangles = &triangles, g.max_triangles = o.max_triangles;
    g.lipschitz = !scene.raw_field;
    Mesh m;
    if (scene.distance.outputs.empty()) return m;
    tbb::enumerable_thread_specific<Scratch> tls;

    // map: the brick's index in `bricks`, kUnsampled, or kUniform (sampled: no surface).
    constexpr int32_t kUnsampled = -1, kUniform = -2;
    auto progress = [&](double f) {
        if (o.progress) o.progress(o.simplify > 0.0f ? kContouringShare * f : f);
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
        t.mark_min_chains();
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
    // The triangle limit was checked while sampling (the count is exact: two per owned
    // sign-changing edge); vertex indices must also fit 32 bits.
    size_t nverts = 0;
    for (auto& b : bricks) {
        if (nverts + b->verts.size() >= 0xFFFFFFFFu) throw std::runtime_error("the mesh would have over 2^32 vertices");
        b->first_vertex = static_cast<uint32_t>(nverts);
        nverts += b->verts.size();
    }
    tbb::parallel_for(size_t(0), bricks.size(), [&](size_t i) { make_faces(g, *bricks[i], map, bricks); });
    progress(0.95);
    size_t ntris = 0;
    for (auto& b : bricks) ntris += b->tris.size();
    m.positions.reserve(nverts);
    m.triangles.reserve(ntris);
    for (auto& b : bricks) {
        m.positions.insert(m.positions.end(), b->verts.begin(), b->verts.end());
        m.triangles.insert(m.triangles.end(), b->tris.begin(), b->tris.end());
    }
    const size_t made = m.triangles.size();
    if (o.simplify > 0.0f) {
        // The field at the simplifier's probes, each with the tape of the brick it falls in
        // (simplified for that box; made here for bricks sampling skipped), the full tape
        // outside the grid.
        std::unordered_map<size_t, Tape> more;  // the tapes of bricks not sampled
        auto field = [&](const glm::vec3* p, size_t n, Dual* out) {
            std::vector<std::pair<size_t, uint32_t>> order(n);  // (brick + 1, or 0: outside; point)
            for (size_t i = 0; i < n; ++i) {
                const glm::dvec3 c = (glm::dvec3(p[i]) - g.origin) / g.h;
                const glm::ivec3 b = glm::ivec3(glm::floor(c / double(kB)));
                const bool in = glm::all(glm::greaterThanEqual(b, glm::ivec3(0))) && glm::all(glm::lessThan(b, g.bricks));
                order[i] = {in ? g.brick_index(b) + 1 : 0, uint32_t(i)};
            }
            std::sort(order.begin(), order.end());
            std::vector<size_t> start, missing;
            for (size_t i = 0; i < n; ++i) {
                if (i > 0 && order[i].first == order[i - 1].first) continue;
                start.push_back(i);
                const size_t key = order[i].first;
                if (key && map[key - 1] < 0 && !more.count(key - 1)) missing.push_back(key - 1);
            }
            start.push_back(n);
            std::vector<Tape> made(missing.size());
            tbb::parallel_for(size_t(0), missing.size(), [&](size_t k) {
                const size_t bi = missing[k];
                const glm::ivec3 at(int(bi % size_t(g.bricks.x)), int(bi / size_t(g.bricks.x) % size_t(g.bricks.y)),
                                    int(bi / (size_t(g.bricks.x) * size_t(g.bricks.y))));
                made[k] = brick_tape(g, full, at, tls.local());
            });
            for (size_t k = 0; k < missing.size(); ++k) more.emplace(missing[k], std::move(made[k]));
            tbb::parallel_for(size_t(0), start.size() - 1, [&](size_t k) {
                Scratch& s = tls.local();
                const size_t i0 = start[k], i1 = start[k + 1], key = order[i0].first;
                s.x.clear(), s.y.clear(), s.z.clear();
                for (size_t i = i0; i < i1; ++i) {
                    const glm::vec3 q = p[order[i].second];
                    s.x.push_back(q.x), s.y.push_back(q.y), s.z.push_back(q.z);
                }
                const Tape& t = key == 0 ? full : map[key - 1] >= 0 ? bricks[size_t(map[key - 1])]->tape : more.find(key - 1)->second;
                s.field_gradient(g, t.view());
                for (size_t i = i0; i < i1; ++i) out[order[i].second] = s.fg[i - i0];
            });
        };
        SimplifyStats ss;
        simplify_mesh(m, o.simplify, field, &ss, [&](double f) {
            if (o.progress) o.progress(kContouringShare + (1.0 - kContouringShare) * f);
        });
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
        stats->unsimplified_triangles = made;
    }
    return m;
}

}  // namespace sdfc::mesh
