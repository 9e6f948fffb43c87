// The lane window of a Worker's march (marcher.cpp): up to kWindow rays in flight,
// structure of arrays so that the per-step work (point gather, the distance update)
// vectorises, and Buckets, which group the lanes by tape-tree leaf for evaluation.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "runtime/cpu/rays.hpp"
#include "runtime/cpu/tape_tree.hpp"
#include "runtime/eval/vm.hpp"

namespace sdfc::cpu {

// Rays in flight per worker (a multiple of kBatch). 256, a 16 x 16 tile's camera rays:
// fuller leaf groups and more tree walks overlapping than at 128 (colonnade.vm 0.959x on 1
// thread, showcase.sdf 0.962x, recursive1.sdf 0.968x, the 10,000-sphere grid 0.969x; the
// same pictures); 512 was slower again (1.19x colonnade.vm on 2 threads).
constexpr int kWindow = 256;
static_assert(kWindow % kBatch == 0);

// Finished lanes are refilled with the last lane (swap-remove) and then from the queue.
// With a tape tree, each lane caches the leaf holding its point (box and interval), and
// lanes are evaluated grouped by leaf.
//
// Every march keeps its own per-lane state in the six slots a, b, w, om, pr, sl (plain
// floats, so that loading and moving a lane stays one fixed set of copies):
//
//   march         a = last signed distance (inf after a failed relaxed step)
//                 om, pr, sl = over-relaxation: factor omega, previous radius |d|, last step
//   shadow_hard   a = last distance;  om, pr, sl as march
//   shadow_soft   a = res, the smallest cone fraction so far;  b = previous positive
//                 distance (1e20: none);  w = the light's width (tangent) from the ray;
//                 om, pr, sl as march
//   cone_march    a = smallest d / r in the current edge zone (>= 1: none);  b = its t;
//                 w = 1 when the ray ended as a hit
//   march_raw     a = previous t (< 0: none yet), the bracket's outside end while refining;
//                 pr = the value there (NaN: not evaluated);  w, b = the bracket's inside end
//                 and its value;  sl = refinements (0 while marching);
//                 om = 1 when the ray ended as a hit
//
// `sign` is +1 for a ray outside solids, -1 inside (it marches on -d).
struct Lanes {
    alignas(64) float ox[kWindow], oy[kWindow], oz[kWindow], dx[kWindow], dy[kWindow], dz[kWindow];
    // 1 / d per axis (0 where d is 0, or too small to leave a box by: |d| < 1e-30), for exit_t
    // (three divisions a box instead of one a ray).
    alignas(64) float ix[kWindow], iy[kWindow], iz[kWindow];
    alignas(64) float t[kWindow], tmax[kWindow], t0[kWindow], sign[kWindow], w[kWindow], a[kWindow], b[kWindow];
    alignas(64) float om[kWindow], pr[kWindow], sl[kWindow];
    alignas(64) float x[kWindow], y[kWindow], z[kWindow], dist[kWindow];
    alignas(64) float blo[3][kWindow], bhi[3][kWindow], ivlo[kWindow], ivhi[kWindow];  // the lane's leaf
    // Raw fields (Worker::segment_bounds): seg, a lower bound of sign * f on the ray from t
    // to where it leaves its leaf (-inf: none); tested, the last leaf one was sought in.
    alignas(64) float seg[kWindow];
    alignas(64) int32_t steps[kWindow], done[kWindow], idx[kWindow];
    alignas(64) uint32_t ray[kWindow], leaf[kWindow], tested[kWindow];
    alignas(64) uint32_t place[kWindow];  // raw fields: the ray's place in its columns (RayColumns::clear_until)
    void load(int i, const RaySet& rs, uint32_t r, float relax) {
        ox[i] = rs.ox[r], oy[i] = rs.oy[r], oz[i] = rs.oz[r];
        dx[i] = rs.dx[r], dy[i] = rs.dy[r], dz[i] = rs.dz[r];
        ix[i] = inverse(dx[i]), iy[i] = inverse(dy[i]), iz[i] = inverse(dz[i]);
        t[i] = rs.tmin[r], tmax[i] = rs.tmax[r], t0[i] = rs.t0[r];
        sign[i] = rs.inside[r] ? -1.0f : 1.0f;
        w[i] = 0.0f, a[i] = 0.0f, b[i] = 0.0f;
        om[i] = relax, pr[i] = 0.0f, sl[i] = 0.0f;
        steps[i] = 0, done[i] = 0;
        ray[i] = r;
        for (int k = 0; k < 3; ++k) blo[k][i] = INFINITY, bhi[k][i] = -INFINITY;  // no leaf yet
        leaf[i] = 0, ivlo[i] = -INFINITY, ivhi[i] = INFINITY;
        seg[i] = -INFINITY, tested[i] = 0, place[i] = 0;
    }
    void set_leaf(int i, uint32_t id, const TapeTree::Leaf& L) {
        leaf[i] = id;
        seg[i] = -INFINITY;
        for (int k = 0; k < 3; ++k) blo[k][i] = L.lo[k], bhi[k][i] = L.hi[k];
        ivlo[i] = L.ivlo, ivhi[i] = L.ivhi;
    }
    // The leaves of lanes idx[0, m) found again from their points (each from its leaf's
    // neighbour across the face its point is beyond). In passes over all the lanes, so that
    // their loads of tree nodes and leaves overlap instead of waiting one after another.
    void relocate(const int* idx, int m, const TapeTree& T) {
        alignas(64) uint32_t n[kWindow];
        for (int j = 0; j < m; ++j) {
            const int i = idx[j];
            const float lo[3] = {blo[0][i], blo[1][i], blo[2][i]}, hi[3] = {bhi[0][i], bhi[1][i], bhi[2][i]};
            n[j] = T.rope(leaf[i], TapeTree::face_beyond(lo, hi, x[i], y[i], z[i]));
        }
        for (int j = 0; j < m; ++j) {
            __builtin_prefetch(&T.boxes_[n[j]]);
            __builtin_prefetch(&T.nodes[n[j]]);
        }
        for (int j = 0; j < m; ++j) {
            const int i = idx[j];
            n[j] = T.find_from(n[j], x[i], y[i], z[i]);
        }
        for (int j = 0; j < m; ++j) __builtin_prefetch(&T.leaves[n[j]]);
        for (int j = 0; j < m; ++j) set_leaf(idx[j], n[j], T.leaves[n[j]]);
    }
    // Lower bound of sign * d over the lane's leaf, or over its ray's way through the leaf
    // when that is known to be more (seg): > 0 when the lane may jump out of the leaf.
    float slo(int i) const {
        const float s = sign[i] > 0.0f ? ivlo[i] : -ivhi[i];
        return seg[i] > s ? seg[i] : s;
    }
    // Whether a lower bound `lower` around the point leaves the lane's last over-relaxed step in
    // doubt (the spheres may not overlap): the jumps of relaxed marches then step back.
    bool relaxed_doubt(int i, float lower) const { return om[i] > 1.0f && lower + pr[i] < sl[i]; }
    void move(int from, int to) {
        ox[to] = ox[from], oy[to] = oy[from], oz[to] = oz[from];
        dx[to] = dx[from], dy[to] = dy[from], dz[to] = dz[from];
        ix[to] = ix[from], iy[to] = iy[from], iz[to] = iz[from];
        t[to] = t[from], tmax[to] = tmax[from], t0[to] = t0[from], sign[to] = sign[from];
        w[to] = w[from], a[to] = a[from], b[to] = b[from];
        om[to] = om[from], pr[to] = pr[from], sl[to] = sl[from];
        x[to] = x[from], y[to] = y[from], z[to] = z[from], dist[to] = dist[from];
        for (int k = 0; k < 3; ++k) blo[k][to] = blo[k][from], bhi[k][to] = bhi[k][from];
        ivlo[to] = ivlo[from], ivhi[to] = ivhi[from], leaf[to] = leaf[from];
        seg[to] = seg[from], tested[to] = tested[from], place[to] = place[from];
        steps[to] = steps[from], done[to] = done[from], ray[to] = ray[from];
    }
    // Where ray i leaves the box [lo, hi] (its t; possibly a little below t[i] by rounding).
    float exit_t(int i, const float lo[3], const float hi[3]) const {
        float te = INFINITY;
        const float o[3] = {ox[i], oy[i], oz[i]}, inv[3] = {ix[i], iy[i], iz[i]};
        for (int k = 0; k < 3; ++k) {
            if (inv[k] > 0.0f) te = std::min(te, (hi[k] - o[k]) * inv[k]);
            else if (inv[k] < 0.0f) te = std::min(te, (lo[k] - o[k]) * inv[k]);
        }
        return te;
    }
    static float inverse(float d) { return std::fabs(d) >= 1e-30f ? 1.0f / d : 0.0f; }
    // ... its leaf's box.
    float exit_t(int i) const {
        const float lo[3] = {blo[0][i], blo[1][i], blo[2][i]}, hi[3] = {bhi[0][i], bhi[1][i], bhi[2][i]};
        return exit_t(i, lo, hi);
    }
};

// Groups up to kWindow lanes by leaf: order[start[b] .. start[b + 1]) are the lanes of
// bucket b, whose leaf is key_of[b]. Open addressing with generation stamps (no clearing).
struct Buckets {
    static constexpr int kSlots = 1024;
    static_assert(kSlots >= 2 * kWindow);
    uint32_t key[kSlots], gen[kSlots] = {};
    uint16_t id[kSlots];
    uint32_t cur = 0;
    uint32_t key_of[kWindow];
    int count[kWindow + 1], start[kWindow + 1], nb = 0;
    uint16_t bucket[kWindow], order[kWindow];
    void build(const uint32_t* leaf, int n) {
        if (++cur == 0) std::fill_n(gen, kSlots, 0u), cur = 1;
        nb = 0;
        uint32_t last = ~0u;  // (lanes come mostly in runs of one leaf: those skip the table)
        uint16_t last_id = 0;
        for (int i = 0; i < n; ++i) {
            const uint32_t k = leaf[i];
            if (k != last) {
                uint32_t h = (k * 2654435761u) >> 22;  // 10 bits
                while (gen[h] == cur && key[h] != k) h = (h + 1) & (kSlots - 1);
                if (gen[h] != cur) {
                    gen[h] = cur, key[h] = k, id[h] = static_cast<uint16_t>(nb);
                    key_of[nb] = k, count[nb] = 0;
                    ++nb;
                }
                last = k, last_id = id[h];
            }
            bucket[i] = last_id;
            ++count[last_id];
        }
        int acc = 0;
        for (int b = 0; b < nb; ++b) start[b] = acc, acc += count[b];
        start[nb] = acc;
        for (int b = 0; b < nb; ++b) count[b] = start[b];
        for (int i = 0; i < n; ++i) order[count[bucket[i]]++] = static_cast<uint16_t>(i);
    }
};

}  // namespace sdfc::cpu
