// make_frame: one render's Frame, from the render plan (compiler/render/plan.cpp resolves
// every setting: fallbacks, clamps, the clip box and floor planes, the sample pattern, the
// raw-field step) and the CPU's own parts: tiles, the tape tree's leaf 0, the shading code.
// Primary-ray offsets are the plan's, the same in every pixel (tile.cpp reconstructs with a
// box filter); with aa == "cone" one cone per pixel instead.
#include "runtime/cpu/frame.hpp"

#include <algorithm>
#include <cmath>

#include "runtime/eval/vm.hpp"

namespace sdfc::cpu {
namespace {

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
    // The raw-field Lipschitz estimate samples the distance program through the batch VM.
    auto field = [&scene](const float* x, const float* y, const float* z, size_t n, float* out) {
        sample_batch(scene.distance, x, y, z, n, scene.time, out);
    };
    Frame f(scene, plan_for(scene, options.baseline, field));
    f.tile = rules::sdf_tile_size(f.samples);  // ~256+ primary rays, so the lane window stays full
    f.time = scene.time;
    f.view = options.view;
    f.has_distance = !scene.distance.outputs.empty();
    f.has_material = scene.shading.outputs.size() >= static_cast<size_t>(1 + kMatOut);
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
            const float pad = kPad + 0.05f * rules::sdf_max3(f.hi - f.lo);
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
