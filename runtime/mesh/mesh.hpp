// Meshes from a compiled scene: dual contouring on a grid whose empty and full regions the
// interval evaluator skips (runtime/mesh/dual_contour.cpp), and the files they are written
// to (runtime/mesh/mesh_file.cpp).
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "compiler/bytecode/compile.hpp"

namespace sdfc::mesh {

struct Mesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> colors;  // per vertex, linear RGB in [0, 1]; empty when not asked for
    std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

struct MeshOptions {
    // The box meshed. The solid is cut by it, so the mesh is closed even where the surface
    // leaves the box (an infinite plane gets a lid).
    glm::vec3 lo{-1.0f}, hi{1.0f};
    int resolution = 256;  // cells along the longest side of the box
    size_t max_triangles = 50'000'000;
    bool colors = false;  // per-vertex colours from the scene's materials
    float time = 0.0f;
    // Above 0: the mesh is simplified (simplify.hpp), staying this close to the surface.
    float simplify = 0.0f;
    // Called between stages with the fraction of the work done (a progress bar).
    std::function<void(double)> progress;
};

struct MeshStats {
    glm::ivec3 cells{0};        // the grid, padding included
    size_t bricks = 0;          // 8^3-cell blocks of the grid
    size_t active_bricks = 0;   // not proved empty or full by the intervals
    size_t rescued_bricks = 0;  // proved so, but a neighbour's surface reached them
    size_t vertices = 0, triangles = 0;
    size_t unsimplified_triangles = 0;  // as dual contouring made them
};

// The distance to the box [lo, hi] (negative inside): the mesh is of max(scene, box).
inline float box_distance(const glm::vec3& lo, const glm::vec3& hi, const glm::vec3& p) {
    const glm::vec3 c = 0.5f * (lo + hi), e = 0.5f * (hi - lo);
    const glm::vec3 q = glm::abs(p - c) - e;
    return glm::length(glm::max(q, 0.0f)) + glm::min(glm::max(q.x, glm::max(q.y, q.z)), 0.0f);
}

// The gradient of box_distance at p.
inline glm::vec3 box_normal(const glm::vec3& lo, const glm::vec3& hi, const glm::vec3& p) {
    const glm::vec3 c = 0.5f * (lo + hi), e = 0.5f * (hi - lo), s = glm::sign(p - c);
    const glm::vec3 q = glm::abs(p - c) - e;
    const glm::vec3 out = glm::max(q, 0.0f);
    const float l = glm::length(out);
    if (l > 0.0f) return s * out / l;
    const int a = q.x >= q.y && q.x >= q.z ? 0 : (q.y >= q.z ? 1 : 2);
    glm::vec3 n(0.0f);
    n[a] = s[a] != 0.0f ? s[a] : 1.0f;
    return n;
}

// Cells in the grid for these options (padding included): checked against a limit before
// the work starts.
double grid_cells(const MeshOptions& o);

// Throws std::runtime_error when the mesh would have more than max_triangles.
Mesh mesh_scene(const CompiledScene& scene, const MeshOptions& o, MeshStats* stats = nullptr);

// The default box: the scene's bounds with a 2% margin (floor planes aside: the box of the
// rest, which cuts a floor into a thin base), a .vm model's [-1, 1]^3. Where the scene's
// shapes give no bounds (a custom field), the intervals find them (auto_box.cpp). False
// when the scene is unbounded (an infinite repetition, only a plane): --bounds is needed.
// A scene the intervals prove empty everywhere gets [-1, 1]^3 (its mesh is empty).
// `search_cells` caps the interval search's frontier (its cost; the fuzz target keeps it small).
// `resolution` (cells along the longest side, 0: unknown): with floors, the margin is at least
// two cells, so the base is thick enough to be sampled.
bool default_box(const CompiledScene& scene, glm::vec3& lo, glm::vec3& hi, float time = 0.0f, size_t search_cells = 8192,
                 int resolution = 0);

// A box holding every point the interval evaluator does not prove outside, searched within
// [-kSearch, kSearch]^3 to about 1/32 of the solid's size; false if that reaches the search
// cube's faces (no bounded solid) or finds nothing. A distance bound (lipschitz) is also
// bounded by its value at each cell's centre.
inline constexpr float kSearch = 1.0e4f;
// `nothing`: set when false because every cell was proved outside.
bool interval_box(const Program& distance, bool lipschitz, float time, glm::vec3& lo, glm::vec3& hi, size_t max_cells = 8192,
                  bool* nothing = nullptr);

}  // namespace sdfc::mesh
