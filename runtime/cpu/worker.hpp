// Worker: one render thread's tracer. It owns one batch Evaluator for the distance tapes
// and one for the shading program, the lane window and all scratch, built once and reused
// tile after tile (no allocation once warm), so a tile's result depends only on the tile.
// Its parts: marcher.cpp (the lane-window loop and every march), shade.cpp (normals,
// materials, lights, bounces), tile.cpp (one tile from primary rays to pixels).
#pragma once
#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/cpu/frame.hpp"
#include "runtime/cpu/lanes.hpp"
#include "runtime/cpu/rays.hpp"
#include "runtime/eval/interval.hpp"
#include "runtime/eval/vm.hpp"
#include "runtime/io/image.hpp"

namespace sdfc::cpu {

constexpr int kConeEvents = 4;  // partial hits a cone composites (cone_march)

class Worker {
public:
    explicit Worker(const Frame& f) : f_(f), T_(*f.tree), dist_(f.max_regs) {
        if (f.has_material) shade_ = std::make_unique<BatchVM>(f.scene->shading.num_regs);
        lanes_ = std::make_unique<Lanes>();
        buckets_ = std::make_unique<Buckets>();
    }

    // Pixels [x0, x1) x [y0, y1) of img and of the AOV planes that are not null (tile.cpp).
    // Pixels (x, y) go to row y - row0 of img and the planes (a band of the picture).
    void render_tile(int x0, int y0, int x1, int y1, Image& img, AovPlane* depth, AovPlane* normal, AovPlane* steps, int row0 = 0);

    RenderStats stats;

private:
    const Frame& f_;
    const TapeTree& T_;
    BatchVM dist_;  // runs the tapes of T_, its register file big enough for all
    std::unique_ptr<BatchVM> shade_;

    // Scratch, reused tile after tile (no allocation once warm).
    RaySet rays_, next_, hits_, shadow_;
    std::vector<float> t_, accum_, px_, py_, pz_, pd_, nx_, ny_, nz_, mat_, vis_, sw_;
    std::vector<uint8_t> hit_;
    std::vector<int> steps_;
    std::vector<float> prim_depth_, prim_steps_, prim_n_, prim_aw_;
    std::vector<float> miss_;  // per pixel: the weight of its primary rays that missed (alpha)
    std::vector<float> ev_t_, ev_w_, trans_;
    std::vector<int> ev_n_;
    std::vector<uint32_t> local_, sh_idx_;
    std::vector<float> lw_, lnx_, lny_, lnz_, ao_, lrad_;
    uint32_t pleaf_[kWindow], merged_[kWindow];
    const RayColumns* cols_ = nullptr;  // the columns of the rays march_raw marches (null: none)
    int kind_ = RenderStats::kRays;  // what the distance evaluations are for (stats)
    alignas(64) float gx_[kBatch], gy_[kBatch], gz_[kBatch];

    std::unique_ptr<Lanes> lanes_;
    std::unique_ptr<Buckets> buckets_;
    std::unique_ptr<IntervalEvaluator> seg_iv_;  // raw fields' segment bounds (segment_bounds)

    // Distances at n <= kWindow points that all lie in leaf `id`.
    void eval_leaf(uint32_t id, const float* x, const float* y, const float* z, int n, float* out) {
        const TapeTree::Leaf& lf = T_.leaves[id];
        const TapeView tape = lf.view();
        for (int i0 = 0; i0 < n; i0 += kBatch) {
            const int m = std::min(kBatch, n - i0);
            dist_.eval(tape, x + i0, y + i0, z + i0, m, f_.time);
            std::copy_n(dist_.output(tape), m, out + i0);
        }
        stats.distance_points += static_cast<uint64_t>(n);
        stats.distance_points_by[kind_] += static_cast<uint64_t>(n);
        stats.distance_instructions += static_cast<uint64_t>(n) * lf.len;
    }

    // Distances at n <= kWindow points whose leaves are leaf[0, n): one batch per leaf, but
    // for the leaves whose tapes save less than their own batch costs (regroup).
    void eval_grouped(const float* x, const float* y, const float* z, const uint32_t* leaf, int n, float* out) {
        bool same = true;
        for (int i = 1; i < n; ++i) same &= leaf[i] == leaf[0];
        if (same) return eval_leaf(leaf[0], x, y, z, n, out);
        Buckets& B = *buckets_;
        B.build(leaf, n);
        if (regroup(B, leaf, n)) {
            same = true;
            for (int i = 1; i < n; ++i) same &= merged_[i] == merged_[0];
            if (same) return eval_leaf(merged_[0], x, y, z, n, out);
            B.build(merged_, n);
        }
        for (int b = 0; b < B.nb; ++b) {
            const TapeTree::Leaf& lf = T_.leaves[B.key_of[b]];
            const TapeView tape = lf.view();
            for (int j0 = B.start[b]; j0 < B.start[b + 1]; j0 += kBatch) {
                const int m = std::min(kBatch, B.start[b + 1] - j0);
                const uint16_t* ord = B.order + j0;
                for (int j = 0; j < m; ++j) gx_[j] = x[ord[j]], gy_[j] = y[ord[j]], gz_[j] = z[ord[j]];
                dist_.eval(tape, gx_, gy_, gz_, m, f_.time);
                const float* d = dist_.output(tape);
                for (int j = 0; j < m; ++j) out[ord[j]] = d[j];
            }
            const uint64_t cnt = static_cast<uint64_t>(B.start[b + 1] - B.start[b]);
            stats.distance_points += cnt;
            stats.distance_points_by[kind_] += cnt;
            stats.distance_instructions += cnt * lf.len;
        }
    }

    // Whether some of B's groups had better run with leaf 0's tape (the whole program, with
    // its guards, which gives the same floats everywhere); then merged_ holds the lanes'
    // leaves with those groups' moved to 0. A group's own batch pays for gathering and for
    // its padding lanes (the VM computes lanes in groups of 8): worth it only for a tape
    // clearly shorter than the whole program's (bear.vm's leaves keep 517 of its 525
    // instructions, and splitting its windows into small batches cost a fifth of its time).
    bool regroup(const Buckets& B, const uint32_t* leaf, int n) {
        constexpr uint64_t kGroupCost = 128;  // gathering, scattering, a call: in instruction-lanes
        const uint64_t whole = T_.leaves[0].len;
        bool to_root[kWindow], any = false;
        for (int b = 0; b < B.nb; ++b) {
            const uint32_t id = B.key_of[b];
            const uint64_t c = static_cast<uint64_t>(B.start[b + 1] - B.start[b]), len = T_.leaves[id].len;
            const uint64_t padded = (c + 7) / 8 * 8;
            to_root[b] = id != 0 && (8 * len >= 7 * whole || len * padded + kGroupCost >= whole * c);
            any |= to_root[b];
        }
        if (!any) return false;
        for (int i = 0; i < n; ++i) merged_[i] = to_root[B.bucket[i]] ? 0u : leaf[i];
        return true;
    }

    // Distance at `count` arbitrary points (each batch grouped by leaf).
    void eval_points(const float* x, const float* y, const float* z, size_t count, float* out) {
        if (!T_.active) {
            for (size_t i = 0; i < count; i += kWindow)
                eval_leaf(0, x + i, y + i, z + i, static_cast<int>(std::min<size_t>(kWindow, count - i)), out + i);
            return;
        }
        uint32_t prev = 0;
        for (size_t i0 = 0; i0 < count; i0 += kWindow) {
            const int m = static_cast<int>(std::min<size_t>(kWindow, count - i0));
            for (int j = 0; j < m; ++j) {
                prev = T_.locate_from(prev, x[i0 + j], y[i0 + j], z[i0 + j]);
                pleaf_[j] = prev;
            }
            eval_grouped(x + i0, y + i0, z + i0, pleaf_, m, out + i0);
        }
    }

    // The lane-window loop and its parts (marcher.cpp).
    int locate_lanes(Lanes& L, int n);
    template <class Finish>
    void retire(Lanes& L, int& n, Finish&& finish);
    template <class Init, class Update, class Finish, class Empty, class Skip, class Out>
    void run(const RaySet& rs, Init&& init, Update&& update, Finish&& finish, Empty&& empty, Skip&& skip, Out&& out,
             bool segments = false);
    int segment_bounds(Lanes& L, const int32_t* lanes, int n);
    bool skip_sphere(Lanes& L, int i, float slo, float te);
    template <class Skip>
    bool jump(Lanes& L, int i, Skip& skip);

    // The marches (marcher.cpp): camera and secondary rays, raw fields, cones, shadows.
    void march(const RaySet& rs);
    void march_raw(const RaySet& rs, bool shadow);
    void cone_march(const RaySet& rs);
    void shadow_hard(const RaySet& rs);
    void shadow_soft(const RaySet& rs);
    float tile_cone(int x0, int y0, int x1, int y1, glm::vec3& o, glm::vec3& d, glm::vec2& r) const;
    float tile_start(int x0, int y0, int x1, int y1);
    float tile_start_raw(int x0, int y0, int x1, int y1);
    void raw_shadow_cut(RaySet& rs);

    // Shading (shade.cpp).
    void compute_normals(const RaySet& h);
    void compute_materials(const RaySet& h);
    void shade(const RaySet& h, int gen, RaySet& next);

    void push_primary(RaySet& rs, const Ray& r, float weight, uint32_t prim, float start) {
        float tmin = start, tmax = f_.max_dist;
        f_.clip_ray(r.origin, r.dir, tmin, tmax);
        rs.push(r.origin, r.dir, tmin, tmax, 0.0f, glm::vec3(weight), prim, false);
    }
    void push_secondary(RaySet& rs, const glm::vec3& o, const glm::vec3& d, float path, const glm::vec3& w, uint32_t prim,
                        bool in) {
        float tmin = 0.0f, tmax = f_.max_dist;
        f_.clip_ray(o, d, tmin, tmax);
        rs.push(o, d, tmin, tmax, path, w, prim, in);
    }
    // Adds colour c to the pixel of sample `prim`.
    void add(uint32_t prim, const glm::vec3& c) {
        const size_t p = prim / static_cast<uint32_t>(f_.samples);
        accum_[p * 3 + 0] += c.x;
        accum_[p * 3 + 1] += c.y;
        accum_[p * 3 + 2] += c.z;
    }
    // The same for shading's contributions (shade.cpp), never inlined: c is rounded to float
    // before it is added, where an inlined add would let the compiler fuse its last multiply
    // into the sum (FMA). The pictures have always been made this way; they stay bit-identical.
    [[gnu::noinline]] void add_shaded(uint32_t prim, const glm::vec3& c) { add(prim, c); }
};

}  // namespace sdfc::cpu
