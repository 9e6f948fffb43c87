// render(): one frame of the CPU tracer (tracer.hpp), in the order it runs: the frame
// (make_frame, frame.cpp), the AOV planes, the tape tree (tape_tree.cpp), the tiles on
// the worker threads (worker.hpp), the stats. A 2D model is not traced: its picture is
// raster2d's render_2d, the same image `sdfc render` writes for it.
#include "runtime/cpu/tracer.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "runtime/cpu/frame.hpp"
#include "runtime/cpu/slice.hpp"
#include "runtime/cpu/tape_tree.hpp"
#include "runtime/cpu/tree_cache.hpp"
#include "runtime/cpu/worker.hpp"

namespace sdfc {

const std::vector<std::string>& known_aovs() {
    static const std::vector<std::string> k{"depth", "normal", "steps"};
    return k;
}

namespace {

using Clock = std::chrono::steady_clock;
using ProgressFn = std::function<void(const RenderProgress&)>;

double seconds_since(Clock::time_point start, Clock::time_point t) { return std::chrono::duration<double>(t - start).count(); }

// The AOV planes of `img`, one per name asked for (repeats ignored); null where not asked.
// Throws std::invalid_argument for a name not in known_aovs().
struct AovSet {
    AovPlane *depth = nullptr, *normal = nullptr, *steps = nullptr;

    AovSet(Image& img, const std::vector<std::string>& names) {
        img.aovs.reserve(names.size());  // (the pointers below stay valid)
        for (const std::string& name : names) {
            if (std::find(known_aovs().begin(), known_aovs().end(), name) == known_aovs().end())
                throw std::invalid_argument("unknown AOV '" + name + "' (known: depth, normal, steps)");
            if (img.aov(name)) continue;
            const int ch = name == "normal" ? 3 : 1;
            img.aovs.push_back(AovPlane{name, ch, std::vector<float>(static_cast<size_t>(img.width) * img.height * ch, 0.0f)});
        }
        for (auto& a : img.aovs) {
            if (a.name == "depth") depth = &a;
            if (a.name == "normal") normal = &a;
            if (a.name == "steps") steps = &a;
        }
    }
};

// Runs fn(x0, y0, x1, y1) for every tile x tile square of a width x height image (the last
// row and column clipped), as oneTBB tasks in `arena`, row-major tile indices. `progress`
// (may be empty) is called about every 0.1 s from whichever thread finished a tile (never
// two calls at once), then once at the end from the calling thread, with the wall time
// since `start`.
template <class Fn>
void for_each_tile(tbb::task_arena& arena, int width, int height, int tile, const ProgressFn& progress,
                   Clock::time_point start, Fn&& fn) {
    const int tx = (width + tile - 1) / tile, ty = (height + tile - 1) / tile;
    const int total = tx * ty;
    std::atomic<int> tiles_done{0};
    std::atomic<int64_t> last_report{0};  // ns since start
    std::mutex report;
    auto tile_done = [&](int done) {
        if (!progress) return;
        const auto now = Clock::now();
        const int64_t ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now - start).count();
        if (ns - last_report.load(std::memory_order_relaxed) < 100'000'000) return;
        if (!report.try_lock()) return;
        if (ns - last_report.load(std::memory_order_relaxed) >= 100'000'000) {
            last_report.store(ns, std::memory_order_relaxed);
            progress(RenderProgress{done, total, seconds_since(start, now)});
        }
        report.unlock();
    };
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, total, 1), [&](const tbb::blocked_range<int>& range) {
            for (int t = range.begin(); t != range.end(); ++t) {
                const int x0 = (t % tx) * tile, y0 = (t / tx) * tile;
                fn(x0, y0, std::min(x0 + tile, width), std::min(y0 + tile, height));
                tile_done(tiles_done.fetch_add(1, std::memory_order_relaxed) + 1);
            }
        });
    });
    if (progress) progress(RenderProgress{total, total, seconds_since(start, Clock::now())});
}

// Adds one worker's counts to the render's.
void merge(RenderStats& total, const RenderStats& s) {
    total.distance_points += s.distance_points;
    for (int k = 0; k < RenderStats::kKinds; ++k) total.distance_points_by[k] += s.distance_points_by[k];
    total.shading_points += s.shading_points;
    total.primary_rays += s.primary_rays;
    total.distance_instructions += s.distance_instructions;
    total.shading_instructions += s.shading_instructions;
    total.skips += s.skips;
    total.tile_skips += s.tile_skips;
    total.shadow_cuts += s.shadow_cuts;
    total.segment_skips += s.segment_skips;
    total.column_skips += s.column_skips;
    total.tree_leaves += s.tree_leaves;
    total.interval_boxes += s.interval_boxes;
    total.tree_ms += s.tree_ms;
}

// A 2D model: the Prospero image of render_2d (one channel: white where the field is < 0),
// with its stats (distance points only). It has no AOVs.
Image render_flat(const CompiledScene& scene, const RenderOptions& options, RenderStats* stats) {
    if (!options.aovs.empty())
        throw std::invalid_argument("AOV '" + options.aovs[0] + "': a 2D model's picture has no AOVs");
    const auto start = Clock::now();
    if (stats) *stats = RenderStats{};
    const int w = std::max(scene.render.width, 1), h = std::max(scene.render.height, 1);
    Image img = scene.distance.outputs.empty() ? Image(w, h, 1)  // no field: nothing inside
                                               : render_2d(scene, w, h, options.threads, options.baseline, stats);
    if (options.progress) options.progress(RenderProgress{1, 1, seconds_since(start, Clock::now())});
    return img;
}

}  // namespace

Image render(const CompiledScene& scene, const RenderOptions& options, RenderStats* stats) {
    if (scene.is_2d) return render_flat(scene, options, stats);
    cpu::Frame f = cpu::make_frame(scene, options);
    glm::vec3 root_lo(0.0f), root_hi(0.0f);
    bool thin_layer = false;
    const bool want_tree = cpu::tree_root(f, scene, options, root_lo, root_hi, &thin_layer);

    f.alpha = options.alpha;
    const bool band = options.bands > 0;
    int row0 = 0, row1 = f.height;
    if (band) {
        const int tile_rows = (f.height + f.tile - 1) / f.tile;
        if (options.band < 0 || options.band >= options.bands || options.bands > tile_rows)
            throw std::invalid_argument("band " + std::to_string(options.band) + " of " + std::to_string(options.bands) + ": the picture has " +
                                        std::to_string(tile_rows) + " rows of tiles (" + std::to_string(f.tile) + " pixels each)");
        row0 = int(int64_t(options.band) * tile_rows / options.bands) * f.tile;
        row1 = std::min(int(int64_t(options.band + 1) * tile_rows / options.bands) * f.tile, f.height);
    }
    Image img(f.width, row1 - row0, options.alpha ? 4 : 3);
    if (band) img.row0 = row0, img.full_height = f.height;
    const AovSet aov(img, options.aovs);
    f.want_depth = aov.depth != nullptr;
    f.want_normal = aov.normal != nullptr;
    f.want_steps = aov.steps != nullptr;

    const auto start = Clock::now();
    const int threads = options.threads > 0 ? options.threads : tbb::task_arena::automatic;
    tbb::task_arena arena(threads);
    double tree_ms = 0.0;
    bool tree_reused = false;
    arena.execute([&] {
        if (want_tree) {
            const auto t0 = Clock::now();
            cpu::TreeInputs in;
            in.lo = root_lo, in.hi = root_hi, in.time = f.time, in.lipschitz = !f.raw, in.thin_layer = thin_layer;
            in.samples = static_cast<size_t>(f.width) * static_cast<size_t>(f.height) * static_cast<size_t>(f.samples);
            f.tree = cpu::shared_tree(scene.distance, in, options.reuse_tree, &tree_reused);
            tree_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        }
        // A raw field's rays of the camera and of directional lights go from run to run of
        // their columns (ray_columns.hpp; rays clipped to the box, whose ends are in the root).
        if (f.raw && f.tree->active && f.clip && f.planes.empty()) {
            const bool lights = f.shadows && f.view == RenderView::Shaded;
            if (lights) f.light_columns.resize(f.lights.size());
            const rules::SdfCamera& cam = f.camera.rule_camera();
            tbb::parallel_for(size_t(0), f.lights.size() + 1, [&](size_t k) {
                cpu::ColumnsKey key;
                if (k == f.lights.size()) {
                    if (f.cone) return;
                    key.dir = cam.fwd;
                    if (!cam.ortho) {
                        // (cells of about 2 x 2 pixels)
                        key.central = true, key.u = cam.right, key.v = cam.up, key.eye = cam.eye;
                        key.half_u = cam.half_w, key.half_v = cam.half_h, key.cells_u = (f.width + 1) / 2, key.cells_v = (f.height + 1) / 2;
                    }
                    f.camera_columns = cpu::shared_ray_columns(f.tree, key, options.reuse_tree);
                } else if (lights && f.lights[k].directional) {
                    key.dir = glm::normalize(-f.lights[k].direction);  // (as shade.cpp's shadow rays hold it)
                    f.light_columns[k] = cpu::shared_ray_columns(f.tree, key, options.reuse_tree);
                }
            });
        }
        f.max_regs = std::max<uint32_t>(f.tree->max_regs, std::max<uint32_t>(scene.distance.num_regs, 1));
    });

    tbb::enumerable_thread_specific<std::unique_ptr<cpu::Worker>> workers;
    for_each_tile(arena, f.width, row1 - row0, f.tile, options.progress, start, [&](int x0, int y0, int x1, int y1) {
        std::unique_ptr<cpu::Worker>& w = workers.local();
        if (!w) w = std::make_unique<cpu::Worker>(f);
        w->render_tile(x0, y0 + row0, x1, y1 + row0, img, aov.depth, aov.normal, aov.steps, row0);
    });

    if (stats) {
        *stats = RenderStats{};
        for (auto& w : workers)
            if (w) merge(*stats, w->stats);
        stats->tree_leaves = f.tree->active ? f.tree->leaves.size() - 1 : 0;
        stats->interval_boxes = tree_reused ? 0 : f.tree->boxes;
        stats->tree_ms = tree_ms;
        stats->tree_reused = tree_reused;
    }
    return img;
}

}  // namespace sdfc
