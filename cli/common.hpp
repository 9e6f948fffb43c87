// What the commands share: the safety-limit flags, the one-scene argument, building a
// scene, the camera and render flags, thread counts and the progress bar line. cli/main.cpp
// holds most commands; mesh, bench, preview and watch have files of their own.
#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli/args.hpp"
#include "compiler/base/source.hpp"
#include "compiler/bytecode/compile.hpp"
#include "lang/interpreter.hpp"
#include "runtime/cpu/tracer.hpp"

namespace sdfc::cli {

struct Common {
    InterpretOptions interp;
    long max_pixels = 268'435'456;  // width * height * samples, of one band of `bands` (render --tiles)
    int bands = 1;
    int max_frames = 100000;
    // build() leaves the Scene to the process's exit (or the next build) instead of freeing
    // it: for commands that do little after the build (check), whose time its teardown is.
    bool keep_scene = false;
};

// The safety-limit flags (--max-*), taken out of the arguments.
Common read_common(Args& a);
// The command's one scene file (a usage error for none or several).
std::string one_scene(Args& a, const char* cmd);
// The script's warnings (path:line:col: warning: ...) on standard error.
void print_warnings(const Scene& s);
void print_warnings(const Scene& s, const CompileError* besides);
// The scene's warnings once `compile` (what comes after loading) has run; when it throws a
// CompileError, without those at one of its errors' places (a field's body runs there, so a
// warning that a name in it "has not run" would be wrong).
template <class F>
auto compile_then_warn(const Scene& s, F&& compile) {
    try {
        auto r = compile();
        print_warnings(s);
        return r;
    } catch (const CompileError& e) {
        print_warnings(s, &e);
        throw;
    }
}

// Warnings already printed are printed again (sdfc watch: a new run).
void forget_warnings();
// Loads and compiles a scene at `time`, its distance checked finite.
CompiledScene build(SourceManager& sm, const std::string& path, Common& c, std::optional<float> time);
// "" or why the picture will show nothing of the scene: the camera inside the solid, or
// the scene's bounds wholly outside the view (render warns).
std::string view_problem(const CompiledScene& cs);
// --threads, capped at the machine's hardware threads.
int thread_count(const std::string& v);
// `eval --points FILE`: "x y z" a line (blank lines skipped); a bad line is a located error
// (CompileError: path:line:col, the line, a caret).
void read_points(const std::string& path, size_t max_bytes, std::vector<float>& xs, std::vector<float>& ys, std::vector<float>& zs);
// One progress bar line on standard error, redrawn in place; eta < 0: none.
// Seconds of work before a progress bar shows (1; SDFC_PROGRESS_AFTER sets it, for tests).
double progress_after_s();
// `label` ("frame 3/24") goes after the percentage.
void progress_line(const std::string& target, double frac, double elapsed_s, double eta, const std::string& label = "");

// This task's share of a batch (batch.cpp): items k with k % count == index.
struct Shard {
    int index = 0, count = 1;
    std::string from;  // the scheduler's variable it came from, or ""
};
// --shard I/N, --shard auto (Slurm's SLURM_ARRAY_TASK_*, Kubernetes' JOB_COMPLETION_INDEX with
// SDFC_SHARD_COUNT), or with no flag the scheduler's when a batch of `items` has several.
Shard read_shard(const std::optional<std::string>& flag, size_t items);
// --tiles I/N: band I of N, or nothing.
std::optional<std::pair<int, int>> read_bands(const std::optional<std::string>& flag);
// What a band's picture is (batch.cpp): a hash of the compiled scene, its settings and the
// render's options, that sdfc merge compares.
std::string picture_id(const CompiledScene& cs, const RenderOptions& ro);
int cmd_merge(Args& a);

// The scene flags a command took out of its arguments (flag, value if given): they override
// the script's settings of each scene it compiles (render and bench).
using Overrides = std::vector<std::pair<std::string, std::optional<std::string>>>;
// The camera and render(...) flags (--width, --samples, --camera-position, ...), taken out.
Overrides read_overrides(Args& a);
// Sets them on a compiled scene; the picture's size checked against --max-pixels.
void apply_overrides(CompiledScene& cs, const Overrides& ov, Common& c);

// A 2D model (a .vm of x and y only) renders whole as its sign image: --tiles, --aov,
// --alpha on and --view steps are a UsageError naming the first given; `warn` prints which
// scene flags (camera, samples, shading) change nothing.
struct PictureAsks {
    bool tiles = false, aovs = false, alpha = false, steps = false;
};
void check_2d_render(const std::string& scene, const Overrides& ov, const PictureAsks& asks, bool warn);

// The format -o OUT (or --format) names, checked ("" when the extension says it).
std::string image_format_flag(const std::string& out, const std::optional<std::string>& format);
// `sdfc render` (render_command.cpp).
int cmd_render(Args& a);
int cmd_mesh(Args& a);
// `sdfc bench` (bench_command.cpp): renders timed, one line of figures.
int cmd_bench(Args& a);
// `sdfc preview` (preview_command.cpp): serves the live page until Ctrl-C.
int cmd_preview(Args& a);
// `sdfc watch` (watch_command.cpp): `run` runs one command line, its errors reported.
int cmd_watch(const std::vector<std::string>& args, int (*run)(const std::vector<std::string>&));

// Called first by the thread that runs the command: its heap in transparent huge pages where
// the kernel offers them (cli/heap.cpp: a big script's check is mostly page faults otherwise).
void use_big_pages();

}  // namespace sdfc::cli
