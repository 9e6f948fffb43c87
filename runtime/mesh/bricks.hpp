// The bricks of the mesher (runtime/mesh/dual_contour.cpp has the whole design): the
// grid, a brick's corner values and cell configurations, per-thread scratch, and the
// stages that make the bricks (bricks.cpp): classify and sample them, wake the skipped
// neighbours the surface reaches, flip the pinched faces.
#pragma once
#include <cfloat>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/eval/interval.hpp"
#include "runtime/eval/gradient.hpp"
#include "runtime/eval/vm.hpp"
#include "runtime/mesh/mesh.hpp"

namespace sdfc::mesh::dc {


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
    float box(float x, float y, float z) const { return box_distance(lo, hi, {x, y, z}); }
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

inline int corner_index(int x, int y, int z) { return (z * kC + y) * kC + x; }
inline int cell_index(int x, int y, int z) { return (z * kB + y) * kB + x; }

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
            iv->keep_chains(true);  // (for tapes marked by mark_min_chains)
        }
        return *iv;
    }
    GradientEvaluator grad{64};
    std::vector<Dual> fg;
    // The meshed field max(f, box) and its gradient at the points in x, y, z, into fg.
    void field_gradient(const Grid& g, const TapeView& t) {
        const size_t n = x.size();
        fg.resize(n);
        for (size_t i = 0; i < n; i += kBatch) {
            const int m = static_cast<int>(std::min<size_t>(kBatch, n - i));
            grad.eval(t, x.data() + i, y.data() + i, z.data() + i, m, g.time, fg.data() + i);
            for (int j = 0; j < m; ++j) {
                const glm::vec3 p(x[i + j], y[i + j], z[i + j]);
                const float b = g.box(p.x, p.y, p.z);
                Dual& d = fg[i + j];
                if (d.v < b) {  // the box's side: its gradient
                    const glm::vec3 n = box_normal(g.lo, g.hi, p);
                    d = Dual{b, n.x, n.y, n.z};
                }
            }
        }
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
                if (b >= 0.0f && !(f[i + j] > 0.0f)) f[i + j] = FLT_MIN;  // the box's faces close the mesh
            }
        }
    }
};

// A sample exactly on the surface counts as inside: where two solids touch on a grid plane
// (a box standing on a floor plane, two boxes side by side) the samples between them read 0
// and must join them, not leave two shells. The grid's outer layer is outside the box: > 0.
inline bool inside(float v) { return v <= 0.0f; }

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

struct Region {
    glm::ivec3 at{0};  // in bricks
    int level = 0;     // 2^level bricks per side
    Tape tape;
};

// A brick the intervals did not prove empty or full, sampled: null when it had no surface.
struct Sampled {
    glm::ivec3 at{0};
    std::unique_ptr<Brick> brick;
};

// Every brick the intervals do not prove empty or full, sampled with its simplified tape.
std::vector<Sampled> classify(const Grid& g, const Program& p, tbb::enumerable_thread_specific<Scratch>& tls);
// A brick's corners and cell configurations; null when it has no surface.
std::unique_ptr<Brick> sample(const Grid& g, Region& r, Scratch& s);
// The tape simplified for the box of the brick at `at` (the intervals over it, from `full`).
Tape brick_tape(const Grid& g, const Tape& full, glm::ivec3 at, Scratch& s);
// Marks in `want` the unsampled bricks (map -1) the surface of b reaches.
void neighbours_needed(const Grid& g, const Brick& b, const std::vector<int32_t>& map, std::vector<uint8_t>& want);
// Flips every face pinched on both sides (cube.hpp).
void unpinch(const Grid& g, std::vector<std::unique_ptr<Brick>>& bricks, const std::vector<int32_t>& map);

}  // namespace sdfc::mesh::dc
