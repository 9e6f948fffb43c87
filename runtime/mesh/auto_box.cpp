// The box a mesh is made in, when none is given (mesh.hpp): the scene's bounds, or, for a
// custom field whose bounds the shapes cannot tell, the intervals': an octree over a large
// cube keeps the cells not proved outside (a cell proved inside is kept whole and not
// split), down to 1/32 of the box they span.
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "runtime/eval/interval.hpp"
#include "runtime/eval/tape.hpp"
#include "runtime/eval/vm.hpp"
#include "runtime/mesh/mesh.hpp"

namespace sdfc::mesh {
namespace {

constexpr float kFinest = 1.0f / 32.0f;        // of the box's longest side

struct Cell {
    glm::vec3 lo, hi;
};

}  // namespace

// (max_cells: a level's frontier past it ends the search: no bounded solid, or a coarser box)
bool interval_box(const Program& distance, bool lipschitz, float time, glm::vec3& lo, glm::vec3& hi, size_t max_cells, bool* nothing) {
    if (nothing) *nothing = false;
    if (distance.outputs.empty()) return false;
    Tape tape = Tape::from(distance, 0);
    tape.link();
    struct Evaluators {
        IntervalEvaluator iv;
        BatchVM vm;
        Evaluators(uint32_t regs, uint32_t choices) : iv(regs, choices), vm(regs) {}
    };
    tbb::enumerable_thread_specific<Evaluators> tls(tape.num_regs, tape.choices);
    std::vector<Cell> frontier{{glm::vec3(-kSearch), glm::vec3(kSearch)}};
    glm::vec3 solid_lo(INFINITY), solid_hi(-INFINITY);  // cells proved inside
    const auto grow = [](glm::vec3& a, glm::vec3& b, const Cell& c) { a = glm::min(a, c.lo), b = glm::max(b, c.hi); };
    for (int level = 0; level < 40 && !frontier.empty(); ++level) {
        // Each cell's 8 children through the intervals, 8 cells (64 lanes) at a time.
        std::vector<Cell> kids(frontier.size() * 8);
        std::vector<int8_t> sign(kids.size());  // 1 outside, -1 inside, 0 either
        const size_t per = size_t(kIvLanes) / 8;
        tbb::parallel_for(size_t(0), (frontier.size() + per - 1) / per, [&](size_t blk) {
            Evaluators& e = tls.local();
            IntervalEvaluator* iv = &e.iv;
            BatchVM* vm = &e.vm;
            float bx[6][kIvLanes];
            const size_t c0 = blk * per, c1 = std::min(frontier.size(), c0 + per);
            int n = 0;
            for (size_t c = c0; c < c1; ++c) {
                const glm::vec3 mid = 0.5f * (frontier[c].lo + frontier[c].hi);
                for (int k = 0; k < 8; ++k, ++n) {
                    Cell& kid = kids[c * 8 + size_t(k)];
                    for (int a = 0; a < 3; ++a) {
                        const bool upper = (k >> a) & 1;
                        kid.lo[a] = upper ? mid[a] : frontier[c].lo[a];
                        kid.hi[a] = upper ? frontier[c].hi[a] : mid[a];
                        bx[2 * a][n] = kid.lo[a], bx[2 * a + 1][n] = kid.hi[a];
                    }
                }
            }
            iv->eval(tape, bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], n, time);
            // A distance bound is also within half the diagonal of its value at the centre:
            // that proves far cells outside where the intervals of a smooth blend cannot.
            float cx[kIvLanes], cy[kIvLanes], cz[kIvLanes];
            for (int k = 0; k < n; ++k) cx[k] = 0.5f * (bx[0][k] + bx[1][k]), cy[k] = 0.5f * (bx[2][k] + bx[3][k]), cz[k] = 0.5f * (bx[4][k] + bx[5][k]);
            if (lipschitz) vm->eval(tape.view(), cx, cy, cz, n, time);
            for (int k = 0; k < n; ++k) {
                Interval v = iv->result(k);
                if (lipschitz) {
                    const float diag = glm::length(glm::vec3(bx[1][k] - bx[0][k], bx[3][k] - bx[2][k], bx[5][k] - bx[4][k]));
                    const float c = vm->output(tape.view())[k];
                    if (std::isfinite(c)) v = tighten_by_centre(v, c, diag);
                }
                sign[c0 * 8 + size_t(k)] = v.lo > 0.0f ? 1 : (v.hi < 0.0f ? -1 : 0);  // NaN: either
            }
        });
        std::vector<Cell> next;
        for (size_t i = 0; i < kids.size(); ++i) {
            if (sign[i] < 0) grow(solid_lo, solid_hi, kids[i]);
            if (sign[i] == 0) next.push_back(kids[i]);
        }
        glm::vec3 blo = solid_lo, bhi = solid_hi;
        for (const Cell& c : next) grow(blo, bhi, c);
        if (next.empty()) {
            frontier.clear();
            break;
        }
        const float size = next[0].hi.x - next[0].lo.x;  // every cell of a level is a cube of one size
        const float longest = std::max({bhi.x - blo.x, bhi.y - blo.y, bhi.z - blo.z});
        frontier = std::move(next);
        if (size <= kFinest * longest || frontier.size() > max_cells) break;
    }
    glm::vec3 blo = solid_lo, bhi = solid_hi;
    for (const Cell& c : frontier) grow(blo, bhi, c);
    if (!(blo.x <= bhi.x && blo.y <= bhi.y && blo.z <= bhi.z)) {  // nothing: no solid
        if (nothing) *nothing = true;
        return false;
    }
    if (glm::any(glm::lessThanEqual(blo, glm::vec3(-kSearch))) || glm::any(glm::greaterThanEqual(bhi, glm::vec3(kSearch))))
        return false;  // reaches the search cube: unbounded, or bigger than it
    lo = blo, hi = bhi;
    return true;
}

bool default_box(const CompiledScene& scene, glm::vec3& lo, glm::vec3& hi, float time, size_t search_cells, int resolution) {
    if (scene.raw_field) {
        lo = glm::vec3(-1.0f), hi = glm::vec3(1.0f);
        return true;
    }
    // Floor planes make the bounds infinite: the box around the rest (solid_bounds).
    const Bounds& b = scene.bounds.finite() ? scene.bounds : scene.solid_bounds;
    glm::vec3 blo = b.lo, bhi = b.hi;
    if (!b.finite() || !(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) {
        // The shapes do not tell (a custom field): the intervals, without the floors if any.
        const Program& p = scene.solid.outputs.empty() ? scene.distance : scene.solid;
        bool nothing = false;
        if (!interval_box(p, true, time, blo, bhi, search_cells, &nothing)) {
            if (!nothing || !reads_point(p)) return false;  // (a constant field has no surface to find)
            // Proved empty everywhere (an intersection of shapes apart): a box where the
            // mesh is empty, as it is for a difference that removes all.
            blo = glm::vec3(-1.0f), bhi = glm::vec3(1.0f);
        }
    }
    const glm::vec3 ext = bhi - blo;
    // (a margin of its own size: a part of a micrometre keeps its cells; a point gets 1e-3)
    float longest = std::max({ext.x, ext.y, ext.z});
    if (!(longest > 0.0f)) longest = 1e-3f;
    float m = 0.02f * longest;
    // (a floor at the rest's bounds is cut into a base m thick: one cell or less of it could
    // fall between the samples, leaving no base)
    if (!scene.bounds.finite() && !scene.half_spaces.empty() && resolution > 0)
        m = std::max(m, 2.0f * longest / float(std::max(resolution - 4, 1)));
    lo = blo - m, hi = bhi + m;
    return true;
}

}  // namespace sdfc::mesh
