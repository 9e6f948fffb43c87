// Frame: everything the render's workers share, resolved once per render() from the
// CompiledScene and the RenderOptions (settings with their fallbacks, the clip box or floor
// planes, the sample pattern, the tape tree, the programs), and the ray clipping it decides.
#pragma once
#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "compiler/render/camera.hpp"
#include "compiler/render/plan.hpp"
#include "compiler/render/rules.h"
#include "runtime/cpu/ray_columns.hpp"
#include "runtime/cpu/tape_tree.hpp"
#include "runtime/cpu/tracer.hpp"

namespace sdfc::cpu {

constexpr int kMatOut = kMatChannels;  // material channels after the distance output

// The render plan (compiler/render/plan.hpp: the settings both renderers read) and what
// only the CPU needs: the camera object, tiles, AOV flags, the tape tree, the programs.
struct Frame : RenderPlan {
    const CompiledScene* scene = nullptr;
    Camera camera;
    int tile = 16;  // tile side in pixels (rules.h sdf_tile_size)
    float time = 0.0f;
    bool has_distance = true, has_material = true;
    bool want_depth = false, want_normal = false, want_steps = false;
    bool alpha = false;  // RenderOptions::alpha: the image has a coverage channel
    RenderView view = RenderView::Shaded;
    // Leaf 0 (the full distance program) at least; shared with other renders when kept
    // (tree_cache.hpp), and read-only once built.
    std::shared_ptr<const TapeTree> tree;
    // A raw field's columns (ray_columns.hpp; null or empty: none): the camera's primary
    // rays', and per light, a directional light's shadow rays'.
    std::shared_ptr<const RayColumns> camera_columns;
    std::vector<std::shared_ptr<const RayColumns>> light_columns;
    uint32_t max_regs = 1;          // registers of the longest distance tape: sizes the workers' VMs
    std::vector<Instr> shade_code;  // the shading program without the distance output's code

    // The shading program's material outputs as a tape (shade_code, the program's registers).
    TapeView shade_tape() const {
        const Program& p = scene->shading;
        return TapeView{shade_code.data(), static_cast<uint32_t>(shade_code.size()), p.outputs.data(),
                        static_cast<uint32_t>(p.outputs.size()), p.num_regs};
    }

    Frame(const CompiledScene& s, RenderPlan p)
        : RenderPlan(std::move(p)), scene(&s), camera(s.camera, std::max(s.render.width, 1), std::max(s.render.height, 1)) {}
    Frame(Frame&&) = default;
    Frame(const Frame&) = delete;

    float thr(float path) const { return rules::sdf_thr(eps, path); }
    float footprint(float path) const { return rules::sdf_footprint(camera.footprint_base(), camera.footprint_slope(), path); }
    float bias(const glm::vec3& p, float path) const { return rules::sdf_bias(eps, p, path); }

    // Clips [t_min, t_max] to where surfaces can be (rules.h): the bounding box (clip), or,
    // in a scene with floor planes, the hull of the parts of the ray in the box of
    // everything else (solid_lo/hi, may be empty) or under a plane. An empty interval
    // becomes t_min = +inf.
    void clip_ray(const glm::vec3& o, const glm::vec3& d, float& t_min, float& t_max) const {
        if (!planes.empty()) {
            float a = INFINITY, b = -INFINITY;
            rules::sdf_hull_box(solid_lo, solid_hi, o, d, t_min, t_max, a, b);
            for (const glm::vec4& q : planes) rules::sdf_hull_plane(q, o, d, t_min, t_max, a, b);
            t_min = a, t_max = b;
            if (!(t_min <= t_max)) t_min = INFINITY;
            return;
        }
        if (clip) rules::sdf_clip_box(lo, hi, o, d, t_min, t_max);
    }
};

// The frame of one render: settings, bounds and clipping, the raw-field step estimate, the
// sample offsets, acceleration switches, leaf 0 of the tape tree and the shading code. The
// AOV flags (want_*) and `regs` are set by render() (after the AOVs and the tree).
Frame make_frame(const CompiledScene& scene, const RenderOptions& options);

// Where the tape tree goes: false when the frame gets none (baseline, no distance, a short
// program, a 2D model, or no finite box); else its root box in lo, hi, and in *thin_layer
// whether that box was centred under a thin layer of surfaces (frame.cpp settle_thin_layer).
bool tree_root(const Frame& f, const CompiledScene& scene, const RenderOptions& options, glm::vec3& lo, glm::vec3& hi,
               bool* thin_layer = nullptr);

}  // namespace sdfc::cpu
