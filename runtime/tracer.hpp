// The CPU renderer: sphere tracing of a CompiledScene into a linear-light Image.
//
// Work is split into square tiles (oneTBB parallel_for); each worker thread owns one batch
// Evaluator per program, built once. Within a tile every stage is batched: all rays of the
// tile are marched together through a 64-lane window that is refilled as rays finish, then
// normals (tetrahedron, 4 evals per hit), materials, shadow rays, AO taps and secondary
// rays are evaluated in batches too. A tile's result depends only on the tile, so the
// image is bit-identical for any thread count. See tracer.cpp for the shading model.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "compiler/compile.hpp"
#include "runtime/image.hpp"

namespace sdfc {

enum class RenderView {
    Shaded,  // the picture
    Steps,   // heat map of the primary rays' sphere-tracing step counts (`--view steps`)
};

struct RenderOptions {
    int threads = 0;                // 0 = all hardware threads
    std::vector<std::string> aovs;  // any of "depth", "normal", "steps" (see AovPlane)
    RenderView view = RenderView::Shaded;
};

struct RenderStats {
    uint64_t distance_points = 0;  // points evaluated by the distance program
    uint64_t shading_points = 0;   // points evaluated by the shading (material) program
    uint64_t primary_rays = 0;
};

// The names render() accepts in RenderOptions::aovs.
const std::vector<std::string>& known_aovs();

// Renders scene.render.width x scene.render.height pixels. Throws std::invalid_argument for
// an unknown AOV name. `stats`, when given, receives the evaluation counts.
Image render(const CompiledScene& scene, const RenderOptions& options, RenderStats* stats = nullptr);

}  // namespace sdfc
