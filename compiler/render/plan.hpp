// The render plan: every setting both renderers read, resolved once from a scene and its
// render(...) settings. The CPU tracer (runtime/cpu/frame.cpp) builds its Frame from it;
// the GLSL backend (compiler/glsl/glsl.cpp) prints its constants from it. Clamps, defaults,
// sample offsets, the bounds and clip hull (floor planes included), the raw-field step and
// Lipschitz estimate and the default light rig live here and nowhere else.
#pragma once
#include <functional>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "compiler/bytecode/compile.hpp"

namespace sdfc {

struct RenderPlan {
    int width = 1, height = 1;
    int samples = 1;                 // per pixel (1 with cone anti-aliasing)
    std::vector<glm::vec2> offsets;  // where each sample lies in its pixel (Hammersley)
    float min_weight = 1e-3f;        // secondary rays carrying less (per sample) are not traced
    int max_steps = 256, max_bounces = 3;
    float eps = 1e-4f, max_dist = 100.0f;
    bool shadows = true, ao = true;  // ao: never for raw fields
    float exposure = 1.0f;
    int tonemap = 0;  // 0 none, 1 Reinhard, 2 ACES (rules.h sdf_tonemap)
    bool cone = false;               // cone-traced anti-aliasing (render(aa = "cone"))
    bool is_2d = false;              // a 2D model: the Prospero image
    bool raw = false;                // a raw field (.vm model): no distance bound, sign-change marching
    float relax = 1.5f;              // over-relaxation factor (Keinert et al. 2014; 1 = plain Hart)
    bool premarch = true;            // tile cone pre-marching (CPU)

    // Where surfaces can be: rays are clipped to the box [lo, hi] (clip), or, in a scene with
    // floor planes, to the hull of their parts under a plane n.p <= w or in the box
    // [solid_lo, solid_hi] of everything else (empty when lo > hi). Margins included.
    bool clip = false;
    glm::vec3 lo{0.0f}, hi{0.0f};
    std::vector<glm::vec4> planes;
    glm::vec3 solid_lo{1.0f}, solid_hi{-1.0f};

    // Raw fields: the Lipschitz estimate that scales |f| into steps, and the longest step.
    float raw_lipschitz = 1.0f, raw_max_step = 0.05f;

    // Constant scene settings (the CPU's; GLSL computes them per frame from the same rules):
    // colours made finite and non-negative, the script's lights or the default rig.
    glm::vec3 ambient{0.0f}, background{0.0f};
    std::vector<ResolvedLight> lights;
    bool default_lights = false;  // the script has no light
};

// What the plan is resolved from: the same for a CompiledScene (a fixed time) and for a
// Scene compiled to GLSL (time symbolic: the camera, lights and colours may be unknown).
struct PlanInputs {
    RenderSettings settings;
    SceneBounds bounds;
    bool is_2d = false, raw_field = false, has_distance = true;
    // Constant camera position and target (a raw field without bounds is marched in a cube
    // around the target); absent when they depend on time.
    std::optional<glm::vec3> camera_position, camera_target;
    // The distance field on a batch of points, for the raw-field Lipschitz estimate.
    std::function<void(const float* x, const float* y, const float* z, size_t n, float* out)> field;
    bool baseline = false;  // plain Hart tracing: no relaxation, pre-marching or clipping
};

RenderPlan resolve_plan(const PlanInputs& in);

// The CPU's plan of a compiled scene; `field` evaluates its distance program.
RenderPlan plan_for(const CompiledScene& scene, bool baseline,
                    const std::function<void(const float*, const float*, const float*, size_t, float*)>& field);

// The sample offsets within a pixel: x stratified, y the base-2 radical inverse shifted by
// half a stratum (a Hammersley set).
std::vector<glm::vec2> sample_offsets(int samples);

// The default light rig for a camera (the rule in compiler/render/rules.h).
std::vector<ResolvedLight> default_lights(const ResolvedCamera& camera);

}  // namespace sdfc
