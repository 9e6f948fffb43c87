// Frame: everything the render's workers share, resolved once per render() from the
// CompiledScene and the RenderOptions (settings with their fallbacks, the clip box or floor
// planes, the sample pattern, the tape tree, the programs), and the ray clipping it decides.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "compiler/render/camera.hpp"
#include "runtime/cpu/float_ops.hpp"
#include "runtime/cpu/tape_tree.hpp"
#include "runtime/cpu/tracer.hpp"

namespace sdfc::cpu {

constexpr float kRelax = 1.5f;         // over-relaxed sphere tracing factor (Keinert et al. 2014)
constexpr int kMatOut = kMatChannels;  // material channels after the distance output

struct Frame {
    const CompiledScene* scene = nullptr;
    Camera camera;
    int width = 0, height = 0, samples = 1, tile = 16, max_steps = 256, max_bounces = 3;
    float eps = 1e-4f, max_dist = 100.0f, time = 0.0f;
    bool cone = false, shadows = true, ao = true, has_distance = true, has_material = true;
    bool clip = false;
    // Raw fields (.vm models) make no Lipschitz claim: see march_raw().
    bool raw = false;
    float raw_lipschitz = 1.0f, raw_max_step = 0.05f;
    glm::vec3 lo{0}, hi{0};
    std::vector<glm::vec4> planes;  // floor planes as half-spaces n.p <= w (with a margin)
    glm::vec3 solid_lo{0}, solid_hi{0};  // ... and the box of everything else
    std::vector<glm::vec2> offsets;
    bool want_depth = false, want_normal = false, want_steps = false;
    RenderView view = RenderView::Shaded;
    glm::vec3 ambient{0}, background{0};
    float relax = kRelax;           // over-relaxation factor (1 = plain Hart)
    bool premarch = true;           // tile cone pre-marching (Worker::tile_start)
    TapeTree tree;                  // leaf 0 (the full distance program) at least
    Program regs;                   // no code: sizes the workers' distance register files
    std::vector<Instr> shade_code;  // the shading program without the distance output's code

    explicit Frame(const CompiledScene& s) : scene(&s), camera(s.camera, std::max(s.render.width, 1), std::max(s.render.height, 1)) {}
    Frame(Frame&&) = default;       // (a copy would leave the tree's leaves pointing into the original's tapes)
    Frame(const Frame&) = delete;

    float thr(float path) const { return eps * std::max(path, 1.0f); }
    float footprint(float path) const { return camera.footprint_base() + camera.footprint_slope() * path; }
    float bias(const glm::vec3& p, float path) const { return 4.0f * thr(path) + 2e-5f * (1.0f + maxabs3(p)); }

    // Clips [t_min, t_max] to where surfaces can be: the bounding box (clip), or, in a scene
    // with floor planes, the hull of the parts of the ray in the box of everything else
    // (solid_lo/hi, may be empty) or under a plane (planes). An empty interval becomes
    // t_min = +inf.
    void clip_ray(const glm::vec3& o, const glm::vec3& d, float& t_min, float& t_max) const {
        if (!planes.empty()) return clip_hull(o, d, t_min, t_max);
        if (!clip) return;
        clip_box(lo, hi, o, d, t_min, t_max);
    }
    static void clip_box(const glm::vec3& lo, const glm::vec3& hi, const glm::vec3& o, const glm::vec3& d, float& t_min,
                         float& t_max) {
        for (int a = 0; a < 3; ++a) {
            if (std::fabs(d[a]) < 1e-30f) {
                if (o[a] < lo[a] || o[a] > hi[a]) t_min = INFINITY;
                continue;
            }
            float inv = 1.0f / d[a];
            float t1 = (lo[a] - o[a]) * inv, t2 = (hi[a] - o[a]) * inv;
            if (t1 > t2) std::swap(t1, t2);
            t_min = std::max(t_min, t1);
            t_max = std::min(t_max, t2);
        }
        if (!(t_min <= t_max)) t_min = INFINITY;
    }
    void clip_hull(const glm::vec3& o, const glm::vec3& d, float& t_min, float& t_max) const {
        float a = INFINITY, b = -INFINITY;
        if (solid_lo.x <= solid_hi.x && solid_lo.y <= solid_hi.y && solid_lo.z <= solid_hi.z) {
            float t0 = t_min, t1 = t_max;
            clip_box(solid_lo, solid_hi, o, d, t0, t1);
            if (t0 <= t1) a = t0, b = t1;
        }
        for (const glm::vec4& q : planes) {
            // Under the plane where s + v t <= 0.
            const float s = q.x * o.x + q.y * o.y + q.z * o.z - q.w, v = q.x * d.x + q.y * d.y + q.z * d.z;
            float t0 = t_min, t1 = t_max;
            if (v < 0.0f) t0 = std::max(t0, -s / v);
            else if (v > 0.0f) t1 = std::min(t1, -s / v);
            else if (!(s <= 0.0f)) continue;
            if (t0 <= t1) a = std::min(a, t0), b = std::max(b, t1);
        }
        t_min = a, t_max = b;
        if (!(t_min <= t_max)) t_min = INFINITY;
    }
};

// The frame of one render: settings, bounds and clipping, the raw-field step estimate, the
// sample offsets, acceleration switches, leaf 0 of the tape tree and the shading code. The
// AOV flags (want_*) and `regs` are set by render() (after the AOVs and the tree).
Frame make_frame(const CompiledScene& scene, const RenderOptions& options);

// Where the tape tree goes: false when the frame gets none (baseline, no distance, a short
// program, a 2D model, or no finite box); else its root box in lo, hi.
bool tree_root(const Frame& f, const CompiledScene& scene, const RenderOptions& options, glm::vec3& lo, glm::vec3& hi);

}  // namespace sdfc::cpu
