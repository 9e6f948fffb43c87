// A family of rays' columns through the tape tree, for a raw field's marches
// (Worker::march_raw): the rays of a directional light (parallel, along `dir`) or of a
// pinhole camera (from its eye) are cut into columns, square cells across them, and each
// column keeps the runs of depth along its rays where they may meet a leaf not proven empty
// (a light's: less the pieces of those leaves proven positive, ray_columns.cpp lay_chords).
// Every ray of the family stays inside one column, so a ray leaving an empty leaf (or a
// leaf whose way it has proven clear) goes straight to the start of its column's next run:
// nothing before it can hold a sign change. A ray past its column's last run is done.
//
// Without them, a ray crosses the small empty leaves beside the surfaces one jump at a time
// (colonnade.vm: 6 jumps a shadow ray, most through leaves 7 and 8 levels down).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/cpu/tape_tree.hpp"

namespace sdfc::cpu {

struct RayColumns {
    // Parallel: the rays run along dir (unit); a column is a cell of the plane across it
    // (axes u, v), and depth is s = dot(p, dir).
    // Central: the rays leave `eye`; a column is a cell of the plane z = 1 in the frame
    // (u, v, dir) at the eye (a direction's tangents dot(d, u) / dot(d, dir), ...), and depth
    // is the distance from the eye, which is a ray's t.
    bool central = false;
    glm::vec3 dir{0}, u{0}, v{0}, eye{0};
    float u0 = 0, v0 = 0, inv_cell = 0;
    int nu = 0, nv = 0;
    // Column c's runs start at runs[first[c]] and end at an (inf, inf) (runs[0]: the empty
    // columns').
    std::vector<uint32_t> first;
    std::vector<glm::vec2> runs;  // a column's: sorted, disjoint [lo, hi] of depth, margins included
    glm::vec3 root_lo{0}, root_hi{0};  // where the runs hold (the tree's root, less the margin)

    static constexpr uint32_t kUnknown = ~0u;
    // A ray's place in the columns (for clear_until): first[its column] + 1, or kUnknown when
    // the columns know nothing of it (its end or column outside them, a ray not of the
    // family).
    uint32_t place(const glm::vec3& o, const glm::vec3& d, float t_end) const {
        if (!in_root(o + d * t_end)) return kUnknown;  // (leaf 0 past the root: never skipped)
        float cu, cv;
        if (central) {
            const float w = glm::dot(d, dir);
            if (!(w > 0.0f) || o != eye) return kUnknown;
            cu = glm::dot(d, u) / w, cv = glm::dot(d, v) / w;
        } else {
            if (d != dir) return kUnknown;
            cu = glm::dot(o, u), cv = glm::dot(o, v);
        }
        cu = (cu - u0) * inv_cell, cv = (cv - v0) * inv_cell;
        if (!(cu >= 0.0f && cu < float(nu) && cv >= 0.0f && cv < float(nv))) return kUnknown;
        return first[size_t(int(cv)) * size_t(nu) + size_t(int(cu))] + 1;
    }

    // clear_until for a ray's start, which need not be in the root box: t_start itself when
    // it is not (the columns know nothing of what lies outside), so +inf only for a ray of
    // the family that meets no leaf not proven empty up to t_end.
    float first_run(const glm::vec3& o, const glm::vec3& d, float t_start, float t_end, uint32_t& at) const {
        return in_root(o + d * t_start) ? clear_until(o, d, t_start, t_end, at) : t_start;
    }
    bool in_root(const glm::vec3& p) const {  // (NaN: no)
        return p.x >= root_lo.x && p.x <= root_hi.x && p.y >= root_lo.y && p.y <= root_hi.y && p.z >= root_lo.z && p.z <= root_hi.z;
    }

    // Along the ray o + t d (one of the family's) from t, a point in the root box, as is
    // o + t_end d: the first t' >= t where it may meet a leaf not proven empty (t itself when
    // it may be in one now), or +inf when there is none. `at`: the ray's place (0 before its
    // first call), moved on along its column (t only grows along a ray: a call looks at
    // the runs from the last one's).
    float clear_until(const glm::vec3& o, const glm::vec3& d, float t, float t_end, uint32_t& at) const {
        if (at == 0) at = place(o, d, t_end);
        const float s0 = central ? 0.0f : glm::dot(o, dir), s = s0 + t;
        if (at == kUnknown || !(s == s)) return t;
        uint32_t k = at - 1;
        while (runs[k].y < s) ++k;
        at = k + 1;
        if (!(runs[k].x < INFINITY)) return INFINITY;
        return runs[k].x <= s ? t : std::max(runs[k].x - s0, t);
    }
};

// The columns of the leaves of T that are not proven positive (ivlo > 0), for rays along
// `dir` (unit, and the very floats the rays hold), or, when `central`, for rays from `eye`
// whose tangents in the frame (u, v, dir) lie in [-half_u, half_u] x [-half_v, half_v], in
// about `cells_u` x `cells_v` cells (fewer when the leaves are coarser). Null when T has no
// tree.
struct ColumnsKey {
    bool central = false;
    glm::vec3 dir{0}, u{0}, v{0}, eye{0};
    float half_u = 0, half_v = 0;
    int cells_u = 0, cells_v = 0;
};
std::shared_ptr<const RayColumns> build_ray_columns(const TapeTree& T, const ColumnsKey& key);

// The same, the ones built last for the same tree and key when `keep` (as the tree itself
// is kept: tree_cache.hpp), else built anew (and, when `keep`, kept). Thread-safe.
std::shared_ptr<const RayColumns> shared_ray_columns(const std::shared_ptr<const TapeTree>& T, const ColumnsKey& key, bool keep);

}  // namespace sdfc::cpu
