// make_frame: the settings of one render resolved from the scene and the options. Every
// rule that turns a RenderSettings value into what the tracer uses (fallbacks, clamps, the
// clip box and its margins, the sample pattern) is here, in one function.
//
//  * Primary-ray offsets: `samples` per pixel on a Hammersley pattern ((i+0.5)/S,
//    radical_inverse(i) + 0.5/S), the same pattern in every pixel (tile.cpp reconstructs
//    with a box filter). With aa == "cone" one cone per pixel instead, `samples` ignored.
//  * Raw fields (.vm models): their box, and a Lipschitz estimate that sizes their steps
//    (estimate_lipschitz, march_raw in marcher.cpp).
#include "runtime/cpu/frame.hpp"

#include <algorithm>
#include <cmath>

#include "runtime/eval/vm.hpp"

namespace sdfc::cpu {
namespace {

float radical_inverse2(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x55555555u) << 1) | ((i & 0xAAAAAAAAu) >> 1);
    i = ((i & 0x33333333u) << 2) | ((i & 0xCCCCCCCCu) >> 2);
    i = ((i & 0x0F0F0F0Fu) << 4) | ((i & 0xF0F0F0F0u) >> 4);
    i = ((i & 0x00FF00FFu) << 8) | ((i & 0xFF00FF00u) >> 8);
    return static_cast<float>(i) * 2.3283064365386963e-10f;
}

// A Lipschitz estimate for a raw field over a box: the largest gradient norm (forward
// differences) on a 16^3 grid, among the tenth of the points with the smallest |f| (the far
// field of e.g. a polynomial grows much faster than near its surface, where steps matter),
// times 1.5.
float estimate_lipschitz(const CompiledScene& scene, const glm::vec3& lo, const glm::vec3& hi) {
    constexpr int kGrid = 16;
    Evaluator ev(scene.distance);
    const glm::vec3 ext = hi - lo;
    if (!std::isfinite(max3(ext))) return 1.0f;
    const float e = 1e-3f * std::max(max3(ext), 1e-6f);
    std::vector<float> fx, fy, fz, value, grad;
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
    for (size_t i = 0; i < fx.size(); i += kBatch) {
        const int m = static_cast<int>(std::min<size_t>(kBatch, fx.size() - i));
        ev.eval(fx.data() + i, fy.data() + i, fz.data() + i, m, scene.time);
        std::copy_n(ev.output(0), m, out.data() + i);
    }
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

// The instructions of `p` that outputs [first, end) need (dead code removed, registers
// unchanged, so the outputs stay where they were). Here until runtime/eval has one
// dead-code pass for every tape shape: its only user is the shading code below.
std::vector<Instr> live_code(const Program& p, size_t first) {
    std::vector<uint8_t> need(std::max<size_t>(p.num_regs, 1), 0);
    for (size_t o = first; o < p.outputs.size(); ++o) need[p.outputs[o]] = 1;
    std::vector<Instr> rev;
    for (size_t i = p.code.size(); i-- > 0;) {
        const Instr& in = p.code[i];
        if (!need[in.out]) continue;
        need[in.out] = 0;
        const int ar = kOpInfo[static_cast<int>(in.op)].arity;
        if (ar > 0) need[in.a] = 1;
        if (ar > 1) need[in.b] = 1;
        if (ar > 2) need[in.c] = 1;
        rev.push_back(in);
    }
    return {rev.rbegin(), rev.rend()};
}

}  // namespace

Frame make_frame(const CompiledScene& scene, const RenderOptions& options) {
    Frame f(scene);
    const RenderSettings& rs = scene.render;
    f.width = std::max(rs.width, 1);
    f.height = std::max(rs.height, 1);
    f.cone = rs.aa == "cone";
    f.samples = f.cone ? 1 : std::clamp(rs.samples, 1, 4096);
    f.max_steps = std::max(rs.max_steps, 1);
    f.max_bounces = std::clamp(rs.max_bounces, 0, 64);
    f.eps = std::isfinite(rs.epsilon) && rs.epsilon > 0 ? rs.epsilon : 1e-4f;
    f.max_dist = std::isfinite(rs.max_distance) && rs.max_distance > 0 ? rs.max_distance : 100.0f;
    f.shadows = rs.shadows;
    f.ao = rs.ao;
    f.time = scene.time;
    f.view = options.view;
    f.ambient = glm::vec3(nonneg(scene.ambient.x), nonneg(scene.ambient.y), nonneg(scene.ambient.z));
    f.background = glm::vec3(nonneg(scene.background.x), nonneg(scene.background.y), nonneg(scene.background.z));
    f.has_distance = !scene.distance.outputs.empty();
    f.has_material = scene.shading.outputs.size() >= static_cast<size_t>(1 + kMatOut);
    f.raw = scene.raw_field && f.has_distance;
    if (f.raw) {
        f.cone = false;
        f.samples = std::clamp(rs.samples, 1, 4096);
    }
    if (f.raw && !scene.bounds.finite()) {
        // No bounds and no distance: march within the cube around the camera's target whose
        // half-size is the camera's distance to it (a .vm model's default view frames it).
        const float r = std::max(glm::length(scene.camera.position - scene.camera.target), 1.0f);
        f.lo = scene.camera.target - glm::vec3(r);
        f.hi = scene.camera.target + glm::vec3(r);
        f.clip = std::isfinite(r);
    } else if (scene.bounds.finite()) {
        // A little slack so rays start outside the surface's tolerance band.
        const glm::vec3 ext = scene.bounds.hi - scene.bounds.lo;
        const glm::vec3 margin = glm::vec3(1e-3f * std::max(max3(ext), 0.0f) + 1e-3f);
        f.lo = scene.bounds.lo - margin;
        f.hi = scene.bounds.hi + margin;
        f.clip = f.lo.x <= f.hi.x && f.lo.y <= f.hi.y && f.lo.z <= f.hi.z;
    } else if (!f.raw && !scene.half_spaces.empty()) {
        const Bounds& sb = scene.solid_bounds;
        const bool any = sb.lo.x <= sb.hi.x && sb.lo.y <= sb.hi.y && sb.lo.z <= sb.hi.z;
        const float margin = 1e-3f * (any ? std::max(max3(sb.hi - sb.lo), 0.0f) : 0.0f) + 1e-3f;
        f.solid_lo = any ? sb.lo - margin : glm::vec3(1.0f);
        f.solid_hi = any ? sb.hi + margin : glm::vec3(-1.0f);
        for (const glm::vec4& q : scene.half_spaces) f.planes.emplace_back(glm::vec3(q), q.w + margin + 1e-3f * std::fabs(q.w));
    }
    if (f.raw) {
        f.raw_lipschitz = estimate_lipschitz(scene, f.lo, f.hi);
        f.raw_max_step = f.clip ? glm::length(f.hi - f.lo) / 48.0f : 0.05f * f.max_dist;
    }
    for (int i = 0; i < f.samples; ++i) {
        const float sx = (static_cast<float>(i) + 0.5f) / static_cast<float>(f.samples);
        float sy = radical_inverse2(static_cast<uint32_t>(i)) + 0.5f / static_cast<float>(f.samples);
        if (sy >= 1.0f) sy -= 1.0f;
        f.offsets.emplace_back(sx, sy);
    }
    // Tiles hold ~256+ primary rays so the lane window stays full while rays finish.
    f.tile = f.samples <= 2 ? 16 : (f.samples <= 8 ? 8 : 4);

    // Acceleration: over-relaxation, clipping to the bounds (a raw field needs its box
    // anyway: it is where it is marched) and the tape tree (tree_root, built by render()).
    f.premarch = !f.raw && !f.cone;
    if (options.baseline) {
        f.relax = 1.0f;
        f.premarch = false;
        f.planes.clear();
        if (!f.raw) f.clip = false;
    }
    f.tree.init_full(scene.distance);
    if (f.has_material) f.shade_code = live_code(scene.shading, 1);
    return f;
}

bool tree_root(const Frame& f, const CompiledScene& scene, const RenderOptions& options, glm::vec3& root_lo, glm::vec3& root_hi) {
    bool want_tree = !options.baseline && f.has_distance && !scene.is_2d && scene.distance.code.size() >= kTreeMinProgram;
    if (want_tree) {
        // Around the region rays can reach: the (clip) box with room for normal and AO taps,
        // else a cube around the camera of twice the ray length, cut to the finite sides of
        // the bounds. Points outside run the full program (leaf 0).
        constexpr float kPad = 0.25f;
        if (f.clip) {
            const float pad = kPad + 0.05f * max3(f.hi - f.lo);
            root_lo = f.lo - pad;
            root_hi = f.hi + pad;
        } else {
            const float R = 2.0f * f.max_dist;
            root_lo = scene.camera.position - R;
            root_hi = scene.camera.position + R;
            for (int a = 0; a < 3; ++a) {
                if (scene.bounds.lo[a] > -1e29f) root_lo[a] = std::max(root_lo[a], scene.bounds.lo[a] - kPad);
                if (scene.bounds.hi[a] < 1e29f) root_hi[a] = std::min(root_hi[a], scene.bounds.hi[a] + kPad);
            }
        }
        for (int a = 0; a < 3; ++a) want_tree &= std::isfinite(root_lo[a]) && std::isfinite(root_hi[a]) && root_lo[a] < root_hi[a];
    }
    return want_tree;
}

}  // namespace sdfc::cpu
