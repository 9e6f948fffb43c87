// `sdfc mesh`: dual contouring (runtime/mesh) of one scene into an STL, OBJ, PLY or 3MF file.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "cli/common.hpp"
#include "cli/output_checks.hpp"
#include "runtime/eval/gradient.hpp"
#include "runtime/eval/tape.hpp"
#include "runtime/eval/vm.hpp"
#include "runtime/io/atomic_file.hpp"
#include "runtime/mesh/mesh_file.hpp"

namespace sdfc::cli {
namespace {

// How far the points are off the surface meshed (the scene cut by the box): |f| for a
// distance bound, |f| / |grad f| (to first order) for a raw field, whose values are not
// distances. NaN counts as infinitely far.
std::vector<float> surface_distance(const CompiledScene& cs, const mesh::MeshOptions& mo, const std::vector<glm::vec3>& p) {
    std::vector<float> d(p.size());
    const Tape full = [&] {
        Tape t = Tape::from(cs.distance, 0);
        t.link();
        return t;
    }();
    constexpr size_t B = size_t(kBatch);
    tbb::parallel_for(size_t(0), (p.size() + B - 1) / B, [&](size_t blk) {
        thread_local BatchVM vm(64);
        thread_local GradientEvaluator grad(64);
        const size_t i0 = blk * B, n = std::min(B, p.size() - i0);
        float x[kBatch], y[kBatch], z[kBatch];
        for (size_t j = 0; j < n; ++j) x[j] = p[i0 + j].x, y[j] = p[i0 + j].y, z[j] = p[i0 + j].z;
        Dual g[kBatch];
        if (cs.raw_field) {
            grad.eval(full.view(), x, y, z, int(n), mo.time, g);
        } else {
            vm.eval(full.view(), x, y, z, int(n), mo.time);
            const float* r = vm.output(full.view());
            for (size_t j = 0; j < n; ++j) g[j] = Dual{r[j], 1.0f, 0.0f, 0.0f};
        }
        for (size_t j = 0; j < n; ++j) {
            const float box = mesh::box_distance(mo.lo, mo.hi, p[i0 + j]);
            float v = std::fabs(g[j].v), len = std::sqrt(g[j].dx * g[j].dx + g[j].dy * g[j].dy + g[j].dz * g[j].dz);
            if (!(g[j].v >= box)) v = std::fabs(box), len = 1.0f;  // the box's side (or NaN: below)
            d[i0 + j] = std::isnan(g[j].v) ? INFINITY : v / (len > 1e-6f ? len : 1.0f);
        }
    });
    return d;
}

}  // namespace

// Dual contouring (runtime/mesh): the grid, its memory and the output are checked before
// the work.
int cmd_mesh(Args& a) {
    Common c = read_common(a);
    auto out = a.value("-o", "--output");
    auto res = a.value("--resolution");
    auto cell = a.value("--cell");
    auto bounds = a.value("--bounds");
    auto time_s = a.value("--time");
    auto threads = a.value("--threads");
    auto max_tris = a.value("--max-triangles");
    auto max_cells = a.value("--max-cells");
    auto simplify = a.value("--simplify");
    bool quiet = a.flag("--quiet") | a.flag("-q");  // (both read: either may be given, or both)
    bool error_stats = a.flag("--error");
    auto format = a.value("--format");
    std::string path = one_scene(a, "mesh");
    if (!out) throw UsageError("mesh needs -o OUT (.stl, .obj, .ply or .3mf)");
    if (res && cell) throw UsageError("--resolution and --cell are two ways to say the same: give one");
    mesh::MeshOptions mo;
    if (res) mo.resolution = Args::to_int("--resolution", *res, 1, 16384);
    if (simplify) {
        mo.simplify = Args::to_float("--simplify", *simplify);
        if (!(mo.simplify > 0.0f) || !std::isfinite(mo.simplify))
            throw UsageError(fmt::format("--simplify takes a distance above 0 (the most the mesh may be off the surface), not {}", *simplify));
    }
    if (max_tris) mo.max_triangles = size_t(Args::to_int("--max-triangles", *max_tris, 1, 2000000000));
    double cell_limit = double(1ull << 31);
    if (max_cells) {
        // Up to 2^36 cells (the brick map then takes 512 MB): more than an int holds.
        (void)Args::to_float("--max-cells", *max_cells);  // (its checks of the text; the value as a double: past 2^24 a float rounds)
        cell_limit = std::floor(std::strtod(max_cells->c_str(), nullptr));
        if (!(cell_limit >= 1.0 && cell_limit <= double(1ull << 36)))
            throw UsageError(fmt::format("--max-cells must be from 1 to {}, not {}", 1ull << 36, *max_cells));
    }
    if (*out == "-" && !format) throw UsageError("-o - (standard output) needs --format (stl, obj, ply or 3mf)");
    if (*out == "-" && error_stats) throw UsageError("--error prints to standard output: it cannot go with -o -");
    if (*out != "-" && format)
        throw UsageError(fmt::format("--format is for -o - (standard output); the extension of '{}' names its format", *out));
    const mesh::MeshFormat mf = mesh::mesh_format(*out == "-" ? "stdout." + *format : *out);
    if (mf == mesh::MeshFormat::Unknown)
        throw UsageError(*out == "-" ? fmt::format("--format {}: unknown mesh format (use stl, obj, ply or 3mf)", *format)
                                     : fmt::format("cannot write '{}': unknown mesh format (use .stl, .obj, .ply or .3mf)", *out));
    resolve_output(*out);
    check_not_input(*out, path);
    std::unique_ptr<tbb::global_control> limit;
    if (threads) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, thread_count(*threads));
    SourceManager sm;
    const float t = time_s ? Args::to_float("--time", *time_s) : 0.0f;
    CompiledScene cs = build(sm, path, c, t);
    check_not_input(*out, sm);
    if (cs.is_2d) throw std::runtime_error("mesh needs a 3D scene (this one is 2D: render or slice it)");
    mo.time = t;
    if (bounds) {
        auto f = Args::to_floats("--bounds", *bounds, 6);
        mo.lo = {f[0], f[1], f[2]}, mo.hi = {f[3], f[4], f[5]};
        if (!(mo.lo.x < mo.hi.x && mo.lo.y < mo.hi.y && mo.lo.z < mo.hi.z))
            throw UsageError("--bounds needs X0 < X1, Y0 < Y1 and Z0 < Z1");
        for (float v : f)  // (as the camera: beyond, a float cannot place a vertex within a cell)
            if (!(std::fabs(v) <= 1e15f)) throw UsageError("--bounds must lie within 1e15 of the origin on each axis");
    } else if (!mesh::default_box(cs, mo.lo, mo.hi, t, 8192, mo.resolution)) {
        if (!reads_point(cs.distance)) throw std::runtime_error(fmt::format("{} has no surface (its distance is the same everywhere): nothing to mesh", path));
        throw UsageError("the scene is unbounded (a plane, an infinite repetition, a 2D profile not extruded: extrude(h) it, shapes beyond 1e29?): give --bounds X0,Y0,Z0,X1,Y1,Z1");
    } else if (!(glm::all(glm::lessThanEqual(glm::abs(mo.lo), glm::vec3(1e15f))) && glm::all(glm::lessThanEqual(glm::abs(mo.hi), glm::vec3(1e15f))))) {
        // (as --bounds: beyond, a float cannot place a vertex within a cell, and squares overflow)
        throw std::runtime_error(fmt::format("{} reaches beyond 1e15 of the origin ({} to {}): scale it down to mesh it", path,
                                             fmt::format("{}, {}, {}", mo.lo.x, mo.lo.y, mo.lo.z), fmt::format("{}, {}, {}", mo.hi.x, mo.hi.y, mo.hi.z)));
    }
    const glm::vec3 ext = mo.hi - mo.lo;
    const float longest = std::max({ext.x, ext.y, ext.z});
    if (cell) {
        const float size = Args::to_float("--cell", *cell);
        if (!(size > 0.0f)) throw UsageError("--cell must be positive");
        const double n = std::ceil(double(longest) / size);
        if (n > 16384) throw UsageError(fmt::format("--cell {} makes {} cells across the box, over 16384", *cell, n));
        mo.resolution = std::max(1, int(n));
    }
    if (simplify && !quiet && mo.simplify < 0.04f * longest / float(mo.resolution))
        std::fprintf(stderr, "sdfc: warning: --simplify %s is under 1/25 of a cell (%.3g), the most dual contouring leaves a vertex "
                             "off the surface: few triangles can go\n",
                     simplify->c_str(), 0.04 * double(longest) / mo.resolution);
    const double cells = mesh::grid_cells(mo);
    if (cells > cell_limit)
        throw UsageError(fmt::format("a grid of {:.0f} cells is over the limit of {:.0f} (raise it with --max-cells)", cells, cell_limit));
    mo.colors = mf != mesh::MeshFormat::Stl;
    auto t0 = std::chrono::steady_clock::now();
    bool bar = false;  // as render's: on a terminal, for meshes past a second
    if (!quiet && isatty(fileno(stderr))) {
        mo.progress = [&](double frac) {
            const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            if (s < progress_after_s()) return;
            progress_line(*out, frac, s, -1.0);
            bar = true;
        };
    }
    mesh::MeshStats st;
    mesh::Mesh m = mesh::mesh_scene(cs, mo, &st);
    double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (bar) std::fputs("\r\033[K", stderr);
    write_file(*out, mesh::encode_mesh(m, mf));
    if (error_stats && !m.positions.empty()) {
        std::vector<glm::vec3> centroids;
        for (const auto& tri : m.triangles) centroids.push_back((m.positions[tri[0]] + m.positions[tri[1]] + m.positions[tri[2]]) / 3.0f);
        const std::vector<float> dv = surface_distance(cs, mo, m.positions), dc = surface_distance(cs, mo, centroids);
        const float cell_size = longest / float(mo.resolution);
        double worst = 0.0, sum = 0.0, face_worst = 0.0;
        for (float v : dv) worst = std::max(worst, double(v)), sum += v;
        for (float v : dc) face_worst = std::max(face_worst, double(v));
        write_stdout(fmt::format("triangles {} vertices {} ms {:.1f} max_error_cells {:.4g} mean_error_cells {:.4g} "
                                 "max_centroid_error_cells {:.4g} cell {:.6g}\n",
                                 m.triangles.size(), m.positions.size(), ms, worst / cell_size, sum / double(dv.size()) / cell_size,
                                 face_worst / cell_size, cell_size));
    }
    if (m.triangles.empty())
        std::fprintf(stderr, "sdfc: warning: the mesh of %s is empty: no surface in the box at %d cells across (a finer "
                             "--resolution, or other --bounds?)\n",
                     path.c_str(), mo.resolution);
    if (!quiet)
        std::fprintf(stderr, "sdfc: wrote %s (%zu triangles%s, %zu vertices, %d cells across, %zu of %zu bricks sampled, %.1f ms)\n",
                     *out == "-" ? "standard output" : out->c_str(), m.triangles.size(),
                     simplify ? fmt::format(" simplified from {}", st.unsimplified_triangles).c_str() : "", m.positions.size(),
                     mo.resolution, st.active_bricks + st.rescued_bricks, st.bricks, ms);
    return 0;
}

}  // namespace sdfc::cli
