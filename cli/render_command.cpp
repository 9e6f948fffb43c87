// `sdfc render`: scenes to pictures, or animations (--frames), in batches that a cluster
// splits (--shard, --tiles); every output is checked before any work, and every frame of
// every scene compiles before the first picture is written.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

#include <fmt/format.h>

#include "cli/args.hpp"
#include "cli/common.hpp"
#include "cli/options.hpp"
#include "cli/output_checks.hpp"
#include "cli/output_names.hpp"
#include "compiler/bytecode/compile.hpp"
#include "runtime/io/image.hpp"
#include "runtime/cpu/slice.hpp"
#include "runtime/cpu/tracer.hpp"

namespace sdfc::cli {

int cmd_render(Args& a) {
    Common c = read_common(a);
    auto out = a.value("-o", "--output");
    auto time_s = a.value("--time");
    auto frames = a.value("--frames");
    auto fps_s = a.value("--fps");
    auto aov = a.value("--aov");
    auto threads = a.value("--threads");
    auto view = a.value("--view");
    bool quiet = a.flag("--quiet") | a.flag("-q");  // (both read: either may be given, or both)
    bool baseline = a.flag("--baseline");  // hidden: every acceleration off (issue 6)
    auto format = a.value("--format");
    auto alpha = a.value("--alpha");
    auto shard_s = a.value("--shard");
    auto tiles = a.value("--tiles");
    const bool skip_existing = a.flag("--skip-existing");
    // Overrides are read per scene below; take them out of the positionals first.
    Overrides ov = read_overrides(a);
    auto scenes = a.positionals();
    if (scenes.empty()) throw UsageError("render needs a scene file");
    if (!out) throw UsageError("render needs -o OUT");
    const std::string fmt_ext = image_format_flag(*out, format);
    RenderOptions ro;
    ro.baseline = baseline;
    if (threads) ro.threads = thread_count(*threads);
    // Coverage as alpha: on for EXR unless --alpha off; --alpha on for the other formats that hold it.
    std::string ext = fmt_ext.empty() ? std::filesystem::path(*out).extension().string() : "." + fmt_ext;
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
    const auto bands = read_bands(tiles);
    if (bands) {
        if (ext != ".exr") throw UsageError("--tiles writes a band of the picture as exr (for sdfc merge): -o PART.exr");
        ro.band = bands->first, ro.bands = bands->second;
        c.bands = bands->second;
    }
    ro.alpha = ext == ".exr" && !bands;  // a band holds what the merged picture will: alpha if asked
    if (alpha) {
        if (*alpha != "on" && *alpha != "off") throw UsageError(fmt::format("--alpha takes on or off, not '{}'", *alpha));
        ro.alpha = *alpha == "on";
        const bool holds = ext == ".exr" || ext == ".png" || ext == ".tif" || ext == ".tiff" || ext == ".tga";
        if (ro.alpha && !holds)
            throw UsageError(fmt::format("--alpha on: {} has no alpha channel (exr, png, tif and tga have)", ext.empty() ? *out : ext.substr(1)));
    }
    if (aov) {
        std::stringstream ss(*aov);
        for (std::string item; std::getline(ss, item, ',');) {
            const auto& known = known_aovs();
            if (std::find(known.begin(), known.end(), item) == known.end())
                throw UsageError(fmt::format("unknown AOV '{}' (known: depth, normal, steps)", item));
            ro.aovs.push_back(item);
        }
    }
    if (view) {
        if (*view == "steps") ro.view = RenderView::Steps;
        else if (*view != "shaded") throw UsageError(fmt::format("--view takes shaded or steps, not '{}'", *view));
    }
    if (*out != "-") (void)expand(*out, 0, "");  // (a malformed placeholder first)
    int f0 = 0, f1 = 0;
    float fps = 24.0f;
    bool animated = frames.has_value();
    if (frames) {
        size_t colon = frames->find(':');
        if (colon == std::string::npos) throw UsageError("--frames takes A:B");
        f0 = Args::to_int("--frames", frames->substr(0, colon), 0, 1000000000);
        f1 = Args::to_int("--frames", frames->substr(colon + 1), 0, 1000000000);
        if (f1 < f0) throw UsageError("--frames A:B needs A <= B");
        if (f1 - f0 + 1 > c.max_frames)
            throw UsageError(fmt::format("{} frames is over the limit of {} (raise it with --max-frames)", f1 - f0 + 1, c.max_frames));
        if (f1 > f0 && *out == "-")
            throw UsageError("standard output (-o -) takes one picture: give the frames a file name with {frame:04d}");
        if (f1 > f0 && expand(*out, f0, "") == expand(*out, f0 + 1, ""))
            throw UsageError("rendering several frames needs {frame:04d} in the output name");
    }
    if (fps_s) {
        fps = Args::to_float("--fps", *fps_s);
        if (!(fps > 0)) throw UsageError(fmt::format("--fps must be positive, not {}", *fps_s));
    }
    if (scenes.size() > 1 && *out == "-")
        throw UsageError("standard output (-o -) takes one picture: give the scenes a file name with {name}");
    if (scenes.size() > 1 && out->find("{name}") == std::string::npos)
        throw UsageError("rendering several scenes needs {name} in the output name");
    const size_t items = scenes.size() * size_t(f1 - f0 + 1);
    if (items > 1) check_distinct_outputs(*out, scenes, f0, f1, ro.aovs);
    if (bands && items > 1) throw UsageError("--tiles renders one band of one picture: give one scene and one frame");
    const Shard shard = read_shard(shard_s, items);
    // Item k (the scenes' frames in order) is this task's when k % count == index.
    auto mine = [&](size_t scene, int f) { return (scene * size_t(f1 - f0 + 1) + size_t(f - f0)) % size_t(shard.count) == size_t(shard.index); };
    size_t my_items = 0;
    for (size_t k = 0; k < items; ++k) my_items += k % size_t(shard.count) == size_t(shard.index);
    if (!shard.from.empty() && !quiet)
        std::fprintf(stderr, "sdfc: shard %d/%d (%s): %zu of %zu pictures\n", shard.index, shard.count, shard.from.c_str(), my_items, items);
    else if (my_items == 0 && !quiet)  // (more tasks than pictures: not an error, but say so)
        std::fprintf(stderr, "sdfc: shard %d/%d: none of the %zu pictures\n", shard.index, shard.count, items);
    if (*out == "-" && !ro.aovs.empty() && fmt_ext != "exr")
        throw UsageError("--aov to standard output needs --format exr (as channels: side files need a file name)");
    // Each of this task's outputs can be written (folder, format, not a directory...) and is
    // no scene of the batch, before any work; no import either, once the batch compiled.
    InputFiles inputs;
    for (const std::string& path : scenes) inputs.add(path, true);
    auto check_outputs = [&](bool writable) {
        for (size_t i = 0; i < scenes.size(); ++i) {
            const std::string name = scene_name(scenes[i]);
            for (int f = f0; f <= f1; ++f) {
                if (!mine(i, f)) continue;
                const std::string target = expand(*out, f, name);
                if (writable) check_picture_output(target, fmt_ext);
                inputs.check(target);
                if (!is_exr(target) && target != "-")
                    for (const std::string& av : ro.aovs) {
                        if (writable) check_image_output(aov_side_path(target, av));
                        inputs.check(aov_side_path(target, av));
                    }
            }
        }
    };
    check_outputs(true);
    const PictureAsks asks{bands.has_value(), !ro.aovs.empty(), alpha && ro.alpha, ro.view == RenderView::Steps};
    float base_time = time_s ? Args::to_float("--time", *time_s) : 0.0f;
    // Every scene and import is read once, for all frames (a save during the batch waits
    // for the next run).
    const auto snapshot = std::make_shared<SourceSnapshot>();
    auto compile_frame = [&](SourceManager& sm, const std::string& path, int f) {
        float t = animated ? base_time + float(f) / fps : base_time;
        if (!std::isfinite(t)) throw UsageError(fmt::format("frame {}'s time ({} + {} / {}) is not a finite number", f, base_time, f, fps));
        CompiledScene cs;
        try {
            cs = build(sm, path, c, t);
        } catch (const CompileError& e) {
            if (!animated || f1 == f0) throw;
            std::vector<Diagnostic> d = e.diagnostics();
            for (auto& x : d) x.message += fmt::format(" (at frame {}, time {})", f, t);
            throw CompileError(std::move(d));
        }
        apply_overrides(cs, ov, c);
        return cs;
    };
    // With several outputs, every frame of every scene compiles before the first image is
    // written: an error at any frame leaves no output at all (LANGUAGE.md section 9).
    // A picture already there is complete (written whole or not at all): --skip-existing
    // leaves it (a re-run task, a farm's retry).
    // (An empty file is none of ours, which are written whole: made by `touch`, or a tool
    // that failed. It is rendered.)
    auto present = [&](const std::string& target) {
        std::error_code ec;
        if (target == "-" || !std::filesystem::is_regular_file(target, ec)) return false;
        if (std::filesystem::file_size(target, ec) == 0 || ec) return false;
        if (!is_exr(target))
            for (const std::string& av : ro.aovs)
                if (!std::filesystem::is_regular_file(aov_side_path(target, av), ec)) return false;
        return true;
    };
    auto todo = [&](size_t scene, int f) {
        return mine(scene, f) && !(skip_existing && present(expand(*out, f, scene_name(scenes[scene]))));
    };
    if (my_items > 1)
        for (size_t i = 0; i < scenes.size(); ++i)
            for (int f = f0; f <= f1; ++f) {
                if (!todo(i, f)) continue;
                SourceManager sm(snapshot);
                if (compile_frame(sm, scenes[i], f).is_2d) check_2d_render(scenes[i], ov, asks, false);
            }
    if (my_items > 1) {
        for (const auto& [path, text] : snapshot->texts) inputs.add(path, false);
        check_outputs(false);
    }
    // One bar for the whole batch (frames of several scenes): "frame 3/24", the ETA of all.
    int total = 0;
    for (size_t i = 0; i < scenes.size(); ++i)
        for (int f = f0; f <= f1; ++f) total += todo(i, f);
    const auto batch_t0 = std::chrono::steady_clock::now();
    int done = 0;
    bool bar = false;  // drawn: cleared before the next summary line
    const bool tty = !quiet && isatty(fileno(stderr));
    for (size_t scene = 0; scene < scenes.size(); ++scene) {
        const std::string& path = scenes[scene];
        std::string name = scene_name(path);
        for (int f = f0; f <= f1; ++f) {
            if (!mine(scene, f)) continue;
            std::string target = expand(*out, f, name);
            if (skip_existing && present(target)) {
                if (!quiet) std::fprintf(stderr, "sdfc: skipped %s (it is there)\n", target.c_str());
                continue;
            }
            SourceManager sm(snapshot);
            CompiledScene cs = compile_frame(sm, path, f);
            check_not_input(target, sm);
            if (!is_exr(target) && target != "-")
                for (const std::string& av : ro.aovs) check_not_input(aov_side_path(target, av), sm);
            // A progress bar with ETA on a terminal, for renders (or batches) past a second;
            // the summary line below either way (unless --quiet).
            const std::string shown = total > 1 ? *out : target;
            const std::string label = total > 1 ? fmt::format("frame {}/{}", done + 1, total) : "";
            if (tty) {
                ro.progress = [&](const RenderProgress& p) {
                    if (p.tiles_total <= 0 || p.tiles_done >= p.tiles_total) return;
                    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - batch_t0).count();
                    if (elapsed < progress_after_s()) return;
                    const double frac = (done + double(p.tiles_done) / double(p.tiles_total)) / total;
                    progress_line(shown, frac, elapsed, frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0, label);
                    bar = true;
                };
            }
            if (cs.is_2d) check_2d_render(path, ov, asks, !quiet && f == f0);
            if (!quiet && f == f0)  // once per scene
                if (const std::string why = view_problem(cs); !why.empty()) std::fprintf(stderr, "sdfc: warning: %s\n", why.c_str());
            auto t0 = std::chrono::steady_clock::now();
            Image img;
            try {
                img = cs.is_2d ? render_2d(cs, cs.render.width, cs.render.height, ro.threads, baseline) : render(cs, ro);
            } catch (const std::invalid_argument& e) {  // (render's: options the picture cannot take, --tiles, --aov)
                throw UsageError(e.what());
            }
            double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            if (bar) std::fputs("\r\033[K", stderr), bar = false;
            if (bands) img.picture = picture_id(cs, ro);
            write_image(target, img, WriteOptions{true, fmt_ext});
            ++done;
            if (!quiet)
                std::fprintf(stderr, "sdfc: wrote %s (%dx%d, %.1f ms)\n", target == "-" ? "standard output" : target.c_str(), img.width,
                             img.height, ms);
            // Between the frames of a batch too (a frame may take under the bar's 0.1 s).
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - batch_t0).count();
            if (tty && total > 1 && done < total && elapsed >= progress_after_s()) {
                const double frac = double(done) / total;
                progress_line(*out, frac, elapsed, elapsed * (1.0 - frac) / frac, fmt::format("frame {}/{}", done + 1, total));
                bar = true;
            }
        }
    }
    return 0;
}

}  // namespace sdfc::cli
