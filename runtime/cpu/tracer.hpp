// The CPU renderer: sphere tracing of a CompiledScene into a linear-light Image.
//
// Work is split into square tiles (oneTBB parallel_for); each worker thread owns one batch
// Evaluator per program, built once. Within a tile every stage is batched: all rays of the
// tile are marched together through a 64-lane window that is refilled as rays finish, then
// normals (tetrahedron, 4 evals per hit), materials, shadow rays, AO taps and secondary
// rays are evaluated in batches too. A tile's result depends only on the tile, so the
// image is bit-identical for any thread count.
//
// Acceleration (all off with RenderOptions::baseline): before the tiles, a "tape tree" is
// built once per frame: an octree over the scene whose cells carry the distance program
// shortened for that cell (interval arithmetic + tape simplification, runtime/eval/interval.hpp).
// Every distance evaluation (camera, shadow, secondary rays, normals, AO) runs the tape of
// the leaf cell containing its point, and rays jump over cells the interval proves empty.
// Plus over-relaxed sphere tracing and clipping to the scene's bounding box.
//
// The files, each with its part of the design in its opening comment:
//   tracer.cpp     render(): frame, AOV planes, tape tree, tile scheduling, stats
//   frame.*        Frame, what the workers share: settings resolved once, clipping, samples
//   tape_tree.*    the tape tree and its build
//   worker.hpp     Worker, one thread's tracer and scratch; rays.hpp, lanes.hpp its batches
//   marcher.cpp    the lane-window loop and the marches (camera, cone, raw, shadows)
//   shade.cpp      normals, materials, lights, ambient occlusion, bounces
//   tile.cpp       one tile: primary rays, generations, pixels and AOVs
// 2D models (CompiledScene::is_2d) are not traced: render() returns raster2d's render_2d
// image (slice.hpp).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "compiler/bytecode/compile.hpp"
#include "runtime/io/image.hpp"

namespace sdfc {

enum class RenderView {
    Shaded,  // the picture
    Steps,   // heat map of the primary rays' sphere-tracing step counts (`--view steps`)
};

// Progress of one render(): tiles finished out of all tiles, and the wall time since the
// render began (tape-tree build included).
struct RenderProgress {
    int tiles_done = 0, tiles_total = 0;
    double elapsed_s = 0.0;
};

struct RenderOptions {
    int threads = 0;                // 0 = all hardware threads
    std::vector<std::string> aovs;  // any of "depth", "normal", "steps" (see AovPlane)
    RenderView view = RenderView::Shaded;
    // A fourth channel, alpha: the pixel's coverage by the scene (primary rays that hit);
    // the colour then leaves out the background where the scene does not cover the pixel
    // (premultiplied by alpha, for compositing).
    bool alpha = false;
    // Band `band` of `bands` (bands 0: the whole picture): the rows of tiles split in `bands`
    // runs as even as whole tiles allow. The image is that band (Image::row0 and full_height
    // say where it goes) and its pixels are exactly the whole picture's (sdfc render --tiles).
    int band = 0, bands = 0;
    // Plain Hart sphere tracing on the full program: no tape tree (pruning, empty-space
    // skipping), no over-relaxation, no bounding-box clipping (`--baseline`, for measuring).
    bool baseline = false;
    // Keep the tape tree for the next render that would build the same one, and take the
    // kept one when it is (runtime/cpu/tree_cache.hpp: the same pixels either way; off,
    // every render builds its own). Renders of other scenes replace it.
    bool reuse_tree = true;
    // Called about every 0.1 s while tiles finish, from whichever render thread finished
    // one (never two calls at once), and once at the end with tiles_done == tiles_total
    // from the calling thread. Must not throw.
    std::function<void(const RenderProgress&)> progress;
};

struct RenderStats {
    uint64_t distance_points = 0;  // points evaluated by the distance program
    // ... of which: camera and secondary rays, normals, shadow rays, ambient-occlusion taps
    enum Kind { kRays, kNormals, kShadows, kAo, kKinds };
    uint64_t distance_points_by[kKinds] = {0, 0, 0, 0};
    uint64_t shading_points = 0;   // points evaluated by the shading (material) program
    uint64_t primary_rays = 0;
    // Cost detail (the tracer only): instructions run by the distance and shading
    // evaluations (tape length x points), cells rays jumped over without an evaluation, the
    // leaves a raw field's tiles crossed together before their rays began (tile_start_raw),
    // and the tape tree (leaves, interval boxes evaluated to build it, build wall time).
    uint64_t distance_instructions = 0;
    uint64_t shading_instructions = 0;
    uint64_t skips = 0;
    uint64_t tile_skips = 0;
    uint64_t shadow_cuts = 0;  // a raw field's shadow ray sets cut short (raw_shadow_cut)
    uint64_t segment_skips = 0;  // of skips: a raw field's rays through cells not empty (segment_bounds)
    uint64_t column_skips = 0;   // of skips: a raw field's rays carried on to their column's next run (ray_columns.hpp)
    uint64_t tree_leaves = 0, interval_boxes = 0;
    double tree_ms = 0.0;       // building the tree, or finding the kept one
    bool tree_reused = false;   // the tree was the one kept from an earlier render (RenderOptions::reuse_tree)
};

// The names render() accepts in RenderOptions::aovs.
const std::vector<std::string>& known_aovs();

// Renders scene.render.width x scene.render.height pixels. Throws std::invalid_argument for
// an unknown AOV name. `stats`, when given, receives the evaluation counts.
// A 2D model gives render_2d's one-channel image (white where the field is < 0, options.
// threads and baseline passed on, progress reported once as 1 of 1 tiles, stats: distance
// points only); asking it for any AOV throws std::invalid_argument.
Image render(const CompiledScene& scene, const RenderOptions& options, RenderStats* stats = nullptr);

}  // namespace sdfc
