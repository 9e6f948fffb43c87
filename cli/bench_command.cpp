// `sdfc bench`: renders a scene --repeat times after --warmup untimed ones, then prints one
// line: the median, the fastest and the first render's milliseconds, and what the work was
// (evaluations per pixel by purpose, tape length, the 2D tree's leaves).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <vector>

#include "cli/common.hpp"
#include "runtime/cpu/slice.hpp"
#include "runtime/cpu/tracer.hpp"
#include "runtime/eval/isa.hpp"

namespace sdfc::cli {

int cmd_bench(Args& a) {
    Common c = read_common(a);
    auto repeat = a.value("--repeat");
    auto warmup = a.value("--warmup");
    auto threads = a.value("--threads");
    bool baseline = a.flag("--baseline");
    bool fresh_tree = a.flag("--fresh-tree");
    Overrides ov = read_overrides(a);
    std::string path = one_scene(a, "bench");
    int n = repeat ? Args::to_int("--repeat", *repeat, 1, 100000) : 5;
    const int warm = warmup ? Args::to_int("--warmup", *warmup, 0, 100000) : 2;
    SourceManager sm;
    CompiledScene cs = build(sm, path, c, 0.0f);
    apply_overrides(cs, ov, c);
    RenderOptions ro;
    if (threads) ro.threads = thread_count(*threads);
    ro.baseline = baseline;
    // Every render builds its own tape tree (the cost of one picture), instead of taking the
    // one the render before kept (frames of an animation: runtime/cpu/tree_cache.hpp).
    ro.reuse_tree = !fresh_tree;
    // The first renders of a process pay for fresh memory (page faults on the picture and
    // scratch: twice with glibc, whose first large block is mapped, freed, and then taken
    // from the heap) and thread start-up: --warmup of them run untimed (as hyperfine's
    // --warmup), and the very first one's time is printed apart (cold_ms).
    // A 2D model is prepared once (its root tape and scratch: Raster2d), as an API scene is.
    std::unique_ptr<Raster2d> raster;
    if (cs.is_2d && !baseline && !cs.distance.outputs.empty()) raster = std::make_unique<Raster2d>(cs);
    std::vector<double> ms;
    RenderStats stats;
    double cold = 0.0;
    for (int i = 0; i < warm + n; ++i) {
        RenderStats st;
        auto t0 = std::chrono::steady_clock::now();
        if (raster) raster->render(cs.render.width, cs.render.height, ro.threads, &st);
        else if (cs.is_2d) render_2d(cs, cs.render.width, cs.render.height, ro.threads, baseline, &st);
        else render(cs, ro, &st);
        const double t = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (i == 0) cold = t;
        if (i < warm) continue;
        ms.push_back(t);
        stats = st;
    }
    std::vector<double> sorted = ms;
    std::sort(sorted.begin(), sorted.end());
    double median = sorted.size() % 2 ? sorted[sorted.size() / 2] : 0.5 * (sorted[sorted.size() / 2 - 1] + sorted[sorted.size() / 2]);
    double pixels = double(cs.render.width) * cs.render.height;
    // SDF evaluations (the distance program) per pixel, then what they were for, and the
    // material (shading program) evaluations.
    auto per = [&](uint64_t v) { return double(v) / pixels; };
    const auto& by = stats.distance_points_by;
    std::printf("median_ms=%.3f min_ms=%.3f cold_ms=%.3f evals_per_pixel=%.2f rays=%.2f normals=%.2f shadows=%.2f ao=%.2f "
                "shading=%.2f tape=%.0f/%zu tree_leaves=%llu tree_ms=%.1f tree_reused=%d skips=%.2f segment_skips=%.2f column_skips=%.2f tile_skips=%llu shadow_cuts=%llu "
                "isa=%s\n",
                median, sorted.front(), cold, per(stats.distance_points), per(by[RenderStats::kRays]),
                per(by[RenderStats::kNormals]), per(by[RenderStats::kShadows]), per(by[RenderStats::kAo]),
                per(stats.shading_points),
                stats.distance_points ? double(stats.distance_instructions) / double(stats.distance_points) : 0.0,
                cs.distance.code.size(), static_cast<unsigned long long>(stats.tree_leaves), stats.tree_ms, int(stats.tree_reused), per(stats.skips), per(stats.segment_skips), per(stats.column_skips),
                static_cast<unsigned long long>(stats.tile_skips), static_cast<unsigned long long>(stats.shadow_cuts),
                isa_name(current_isa()));
    return 0;
}

}  // namespace sdfc::cli
