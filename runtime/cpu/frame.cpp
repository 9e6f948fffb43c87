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
    auto full = std::make_shared<TapeTree>();
    full->init_full(scene.distance);
    f.tree = std::move(full);
    if (f.has_material) f.shade_code = live_code(scene.shading, 1);
    return f;
}

namespace {
// A thin layer of surfaces (many small objects on a plane: the content's extent along an
// axis under 1/32 of the root's largest, thinner than the tree's cells usually get) lies
// across the root's midplane on that axis, and so across a split plane of every cell over
// it: twice the surface cells for the tree's node budget. So the root is widened on that
// axis (it covers what it did) to centre just below the layer, which then sits on the
// lower face of its cells at every depth (the 10,000-sphere grid of bench/run at 640 x 360:
// leaf tapes 200 -> 156 instructions a point with the node budget render() then gives,
// 0.79x the time). True when it did.
bool settle_thin_layer(const glm::vec3& clo, const glm::vec3& chi, glm::vec3& root_lo, glm::vec3& root_hi) {
    const float m = rules::sdf_max3(root_hi - root_lo);
    bool thin = false;
    for (int a = 0; a < 3; ++a) {
        if (!(clo[a] >= root_lo[a] && chi[a] <= root_hi[a] && chi[a] - clo[a] < m / 32)) continue;  // (not finite: no)
        const float base = clo[a] - 1e-3f * m, h = std::max(base - root_lo[a], root_hi[a] - base);
        root_lo[a] = base - h;
        root_hi[a] = base + h;
        thin = true;
    }
    return thin;
}
}  // namespace

bool tree_root(const Frame& f, const CompiledScene& scene, const RenderOptions& options, glm::vec3& root_lo, glm::vec3& root_hi,
               bool* thin_layer) {
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
        const bool thin = want_tree && settle_thin_layer(f.clip ? f.lo : scene.bounds.lo, f.clip ? f.hi : scene.bounds.hi, root_lo, root_hi);
        if (thin_layer) *thin_layer = thin;
    }
    return want_tree;
}

}  // namespace sdfc::cpu
