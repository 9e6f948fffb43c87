// Resolving a scene's settings into the render plan both renderers read (plan.hpp).
#include "compiler/render/plan.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "compiler/render/rules.h"

namespace sdfc {
namespace {


// A Lipschitz estimate for a raw field over a box: the largest gradient norm (forward
// differences) on a 16^3 grid, among the tenth of the points with the smallest |f| (the far
// field of e.g. a polynomial grows much faster than near its surface, where steps matter),
// times 1.5.
float estimate_lipschitz(const PlanInputs& in, const glm::vec3& lo, const glm::vec3& hi) {
    constexpr int kGrid = 16;
    const glm::vec3 ext = hi - lo;
    if (!std::isfinite(rules::sdf_max3(ext)) || !in.field) return 1.0f;
    const float e = 1e-3f * std::max(rules::sdf_max3(ext), 1e-6f);
    std::vector<float> fx, fy, fz;
    for (int k = 0; k < kGrid; ++k)
        for (int j = 0; j < kGrid; ++j)
            for (int i = 0; i < kGrid; ++i) {
                const glm::vec3 p = lo + ext * (glm::vec3(i, j, k) + 0.5f) / static_cast<float>(kGrid);
                for (int q = 0; q < 4; ++q) {
                    fx.push_back(p.x + (q == 1 ? e : 0.0f));
                    fy.push_back(p.y + (q == 2 ? e : 0.0f));
                    fz.push_back(p.z + (q == 3 ? e : 0.0f));
                }
            }
    std::vector<float> out(fx.size());
    in.field(fx.data(), fy.data(), fz.data(), fx.size(), out.data());
    std::vector<std::pair<float, float>> samples;  // (|f|, |grad f|)
    for (size_t i = 0; i + 3 < out.size(); i += 4) {
        const glm::vec3 g(out[i + 1] - out[i], out[i + 2] - out[i], out[i + 3] - out[i]);
        const float gn = glm::length(g) / e;
        if (std::isfinite(gn) && std::isfinite(out[i])) samples.emplace_back(std::fabs(out[i]), gn);
    }
    if (samples.empty()) return 1.0f;
    std::sort(samples.begin(), samples.end());
    float l = 0.0f;
    for (size_t i = 0; i < (samples.size() + 9) / 10; ++i) l = std::max(l, samples[i].second);
    return l > 1e-6f ? 1.5f * l : 1.0f;
}

}  // namespace

std::vector<glm::vec2> sample_offsets(int samples) {
    std::vector<glm::vec2> out;
    for (int i = 0; i < samples; ++i) out.push_back(rules::sdf_sample_offset(i, samples));
    return out;
}

std::vector<ResolvedLight> default_lights(const ResolvedCamera& camera) {
    using namespace rules;
    const glm::vec3 fwd = glm::normalize(camera.target - camera.position);
    const glm::vec3 right = glm::normalize(glm::cross(fwd, camera.up));
    const glm::vec3 up = glm::normalize(camera.up);
    ResolvedLight key, fill;
    key.directional = fill.directional = true;
    key.direction = sdf_key_light_dir(fwd, right, up);
    key.color = sdf_key_light_color();
    key.intensity = sdf_key_light_intensity();
    fill.direction = sdf_fill_light_dir(fwd, right, up);
    fill.color = sdf_fill_light_color();
    fill.intensity = sdf_fill_light_intensity();
    return {key, fill};
}

// The far limit when the script sets none: at least the default, far enough for the whole
// scene (its bounds' farthest corner from the camera; with floors, four times the rest's)
// and for four times the camera's distance to its target, so a scene in millimetres works
// as one in metres.
static float fitted_max_distance(const PlanInputs& in, float base) {
    if (!in.camera_position) return base;
    const glm::vec3 cam = *in.camera_position;
    float far = base;
    if (in.camera_target) far = std::max(far, 4.0f * glm::length(*in.camera_target - cam));
    auto farthest = [&](const Bounds& b) {
        float d = 0.0f;
        for (int k = 0; k < 8; ++k) {
            const glm::vec3 c((k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z);
            d = std::max(d, glm::length(c - cam));
        }
        return d;
    };
    const Bounds& b = in.bounds.bounds;
    const Bounds& sb = in.bounds.solid_bounds;
    if (b.finite() && b.lo.x <= b.hi.x) far = std::max(far, 1.01f * farthest(b));
    else if (sb.finite() && sb.lo.x <= sb.hi.x) far = std::max(far, 4.0f * farthest(sb));
    return std::isfinite(far) ? std::min(far, 1e15f) : base;
}

RenderPlan resolve_plan(const PlanInputs& in) {
    RenderPlan p;
    const RenderSettings& rs = in.settings;
    p.width = std::max(rs.width, 1);
    p.height = std::max(rs.height, 1);
    p.raw = in.raw_field && in.has_distance;
    p.is_2d = in.is_2d;
    p.cone = rs.aa == "cone" && !p.raw;
    p.samples = p.cone ? 1 : std::clamp(rs.samples, 1, 4096);
    p.offsets = sample_offsets(p.samples);
    p.min_weight = 1e-3f / static_cast<float>(p.samples);
    p.max_steps = std::max(rs.max_steps, 1);
    p.max_bounces = std::clamp(rs.max_bounces, 0, 64);
    p.eps = std::isfinite(rs.epsilon) && rs.epsilon > 0 ? rs.epsilon : 1e-4f;
    p.max_dist = std::isfinite(rs.max_distance) && rs.max_distance > 0 ? rs.max_distance : 100.0f;
    if (!rs.max_distance_set) p.max_dist = fitted_max_distance(in, p.max_dist);
    p.shadows = rs.shadows;
    p.exposure = std::isfinite(rs.exposure) && rs.exposure > 0.0f ? rs.exposure : 1.0f;
    p.tonemap = rs.tonemap == "aces" ? 2 : rs.tonemap == "reinhard" ? 1 : 0;
    p.ao = rs.ao && !p.raw;

    const Bounds& b = in.bounds.bounds;
    if (p.raw && !b.finite()) {
        // No bounds and no distance: march within the cube around the camera's target whose
        // half-size is the camera's distance to it (a .vm model's default view frames it).
        if (in.camera_position && in.camera_target) {
            const float r = std::max(glm::length(*in.camera_position - *in.camera_target), 1.0f);
            p.lo = *in.camera_target - glm::vec3(r);
            p.hi = *in.camera_target + glm::vec3(r);
            p.clip = std::isfinite(r);
        }
    } else if (b.finite()) {
        // A little slack so rays start outside the surface's tolerance band.
        const glm::vec3 margin = glm::vec3(1e-3f * std::max(rules::sdf_max3(b.hi - b.lo), 0.0f) + 1e-3f);
        p.lo = b.lo - margin;
        p.hi = b.hi + margin;
        p.clip = p.lo.x <= p.hi.x && p.lo.y <= p.hi.y && p.lo.z <= p.hi.z;
    } else if (!p.raw && !in.bounds.half_spaces.empty()) {
        const Bounds& sb = in.bounds.solid_bounds;
        const bool any = sb.lo.x <= sb.hi.x && sb.lo.y <= sb.hi.y && sb.lo.z <= sb.hi.z;
        const float margin = 1e-3f * (any ? std::max(rules::sdf_max3(sb.hi - sb.lo), 0.0f) : 0.0f) + 1e-3f;
        p.solid_lo = any ? sb.lo - margin : glm::vec3(1.0f);
        p.solid_hi = any ? sb.hi + margin : glm::vec3(-1.0f);
        for (const glm::vec4& q : in.bounds.half_spaces)
            p.planes.emplace_back(glm::vec3(q), q.w + margin + 1e-3f * std::fabs(q.w));
    }
    if (p.raw) {
        p.raw_lipschitz = estimate_lipschitz(in, p.lo, p.hi);
        p.raw_max_step = p.clip ? glm::length(p.hi - p.lo) / 48.0f : 0.05f * p.max_dist;
    }
    p.premarch = !p.raw && !p.cone;
    if (in.baseline) {
        p.relax = 1.0f;
        p.premarch = false;
        p.planes.clear();
        if (!p.raw) p.clip = false;
    }
    return p;
}

RenderPlan plan_for(const CompiledScene& scene, bool baseline,
                    const std::function<void(const float*, const float*, const float*, size_t, float*)>& field) {
    PlanInputs in;
    in.settings = scene.render;
    in.bounds = SceneBounds{scene.bounds, scene.solid_bounds, scene.half_spaces};
    in.is_2d = scene.is_2d;
    in.raw_field = scene.raw_field;
    in.has_distance = !scene.distance.outputs.empty();
    in.camera_position = scene.camera.position;
    in.camera_target = scene.camera.target;
    in.field = field;
    in.baseline = baseline;
    RenderPlan p = resolve_plan(in);
    p.ambient = rules::sdf_nonneg3(scene.ambient);
    p.background = rules::sdf_nonneg3(scene.background);
    p.default_lights = scene.lights.empty();
    p.lights = p.default_lights ? default_lights(scene.camera) : scene.lights;
    return p;
}

}  // namespace sdfc
