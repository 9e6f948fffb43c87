// The table of commands and options (options.hpp says who reads it). Defaults that live in
// the code (the limits, render(...)'s settings, the mesher's) are printed from it, not typed.
#include "cli/options.hpp"

#include <fmt/format.h>

#include "compiler/glsl/glsl.hpp"
#include "compiler/scene/scene.hpp"
#include "lang/interpreter.hpp"
#include "runtime/cpu/slice.hpp"
#include "runtime/mesh/mesh.hpp"

namespace sdfc::cli {
namespace {

const char* kImageFormats = "png jpg exr hdr tif tga bmp ppm";

std::vector<Option> render_settings() {
    const RenderSettings r;
    return {
        {"--width", "", "W", "", fmt::format("{}", r.width), "picture width in pixels"},
        {"--height", "", "H", "", fmt::format("{}", r.height), "picture height in pixels"},
        {"--samples", "", "N", "", fmt::format("{}", r.samples), "samples per pixel, for anti-aliasing"},
        {"--camera-position", "", "X,Y,Z", "", "", "where the camera is"},
        {"--camera-target", "", "X,Y,Z", "", "", "the point the camera looks at"},
        {"--fov", "", "DEG", "", "45", "vertical field of view in degrees"},
        {"--max-steps", "", "N", "", fmt::format("{}", r.max_steps), "sphere-tracing steps per ray"},
        {"--max-bounces", "", "N", "", fmt::format("{}", r.max_bounces), "reflection bounces"},
        {"--max-distance", "", "D", "", "fitted to the scene", "how far rays go"},
        {"--epsilon", "", "E", "", fmt::format("{}", r.epsilon), "the distance that counts as a hit"},
        {"--shadows", "", "on|off", "on off", r.shadows ? "on" : "off", "soft shadows"},
        {"--ao", "", "on|off", "on off", r.ao ? "on" : "off", "ambient occlusion"},
        {"--aa", "", "grid|cone", "grid cone", r.aa, "anti-aliasing: stratified samples, or cone tracing"},
        {"--exposure", "", "E", "", fmt::format("{}", r.exposure), "the picture's radiance is multiplied by E before tone mapping"},
        {"--tonemap", "", "none|reinhard|aces", "none reinhard aces", r.tonemap, "tone mapping; none clips at 1"},
    };
}

// The render(...) flags that mean something in a shader (its size is the viewport's, its
// camera the script's or the user's orbit).
std::vector<Option> glsl_settings() {
    std::vector<Option> out;
    for (const Option& o : render_settings())
        if (o.name != "--width" && o.name != "--height" && o.name.rfind("--camera", 0) != 0 && o.name != "--fov") out.push_back(o);
    return out;
}

std::vector<Option> with(std::vector<Option> a, const std::vector<Option>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

std::vector<CommandSpec> make_commands() {
    const Option threads{"--threads", "", "N", "", "all hardware threads", "worker threads"};
    const Option quiet{"--quiet", "-q", "", "", "", "no progress bar and no summary line"};
    const Option time{"--time", "", "T", "", "0", "the script's `time`, in seconds"};
    const Option baseline{"--baseline", "", "", "", "", "plain Hart sphere tracing: every acceleration off (for comparison)"};
    const mesh::MeshOptions m;
    const SliceOptions so;
    std::vector<CommandSpec> c;
    c.push_back({"render", "SCENE... -o OUT", "render scenes to images (or animations: --frames)",
                 with({
                          {"--output", "-o", "OUT", "FILE", "",
                           "the picture; its extension names the format; may hold {frame:04d} (or {frame}) and {name} (the scene's "
                           "file stem, stdin for -), {{ and }} for braces; - is standard output (needs --format)"},
                          {"--format", "", "F", kImageFormats, "", "the image format of standard output (-o -)"},
                          time,
                          {"--frames", "", "A:B", "", "", "frames A to B at --fps, time = --time + frame / fps"},
                          {"--fps", "", "F", "", "24", "frames per second of --frames"},
                          {"--aov", "", "LIST", "depth normal steps", "",
                           "extra planes, comma-separated: depth, normal, steps; in EXR the channels Z (misses: +inf), N.x "
                           "N.y N.z, steps.Y; else side files OUT.NAME.png (OUT.NAME.exr beside hdr)"},
                          {"--view", "", "shaded|steps", "shaded steps", "shaded", "steps: a heat map of the steps each ray took"},
                          {"--alpha", "", "on|off", "on off", "on for exr, else off",
                           "coverage as an alpha channel (exr, png, tif, tga); EXR colour is then premultiplied, 8-bit "
                           "colour straight, and the background left out"},
                          {"--shard", "", "I/N|auto", "", "the scheduler's, for a batch",
                           "render the pictures k (the scenes' frames in order) with k mod N = I; auto: I and N from a Slurm "
                           "job array (SLURM_ARRAY_TASK_ID, _MIN, _COUNT) or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX, "
                           "and SDFC_SHARD_COUNT for N); 0/1: all"},
                          {"--skip-existing", "", "", "", "", "leave pictures that are there already (they are written whole or not at all)"},
                          {"--tiles", "", "I/N", "", "", "render band I of N (rows of whole tiles) into a partial EXR, for sdfc merge"},
                          threads,
                          quiet,
                          baseline,
                      },
                      render_settings()),
                 "The settings flags override the script's camera(...) and render(...). With several frames or scenes, every "
                 "frame of every scene compiles before the first picture is written: an error leaves no output.",
                 true});
    c.push_back({"glsl", "SCENE", "the scene as a GLSL shader (Shadertoy, GLSL 3.30, a WebGL2 page)",
                 with({
                     {"--target", "", "shadertoy|glsl330|html", "shadertoy glsl330 html", "shadertoy",
                      "shadertoy: paste into shadertoy.com; glsl330: a desktop fragment shader; html: one self-contained page "
                      "with an orbit camera"},
                     {"--output", "-o", "OUT", "FILE", "standard output", "the file to write"},
                     {"--code", "", "auto|straight|tape", "auto straight tape", "auto",
                      fmt::format("straight: a GLSL statement per instruction; tape: the programs as data for a small interpreter "
                                  "(the shader's code does not grow with the scene); auto: tape from {} instructions",
                                  kTapeThreshold)},
                     {"--tape-file", "", "PATH", "FILE", "",
                      "glsl330 only: the programs as a tape (as --code tape) that the shader reads from a texture, "
                      "uniform usampler2D sdf_tape, whose data is written to PATH (RGBA32UI, 1024 texels a row, little-endian "
                      "uint32); for big scenes, since NVIDIA's compiler refuses constant arrays over 1,024 texels"},
                 }, glsl_settings()),
                 "The settings flags override the script's render(...); --samples, --max-steps and --max-bounces set the "
                 "#defines at the top of a pasted shader (the html page's controls start from them).",
                 true});
    c.push_back({"compile", "SCENE --emit ast|ir|bytecode", "print a stage of the compiler",
                 {{"--emit", "", "ast|ir|bytecode", "ast ir bytecode", "", "the syntax tree, the IR or the VM's bytecode listing"}}, "",
                 true});
    c.push_back({"check", "SCENE", "report the script's errors and warnings; write nothing", {}, "", true});
    c.push_back({"eval", "SCENE (--at X,Y,Z | --points FILE)", "print the distance at points, one per line",
                 {
                     {"--at", "", "X,Y,Z", "", "", "one point"},
                     {"--points", "", "FILE", "FILE", "", "a file of points, \"x y z\" or \"x,y,z\" per line (-: standard input)"},
                     time,
                 },
                 "", true});
    c.push_back({"slice", "SCENE --axis x|y|z --at V -o OUT", "a picture of the distance field on a plane",
                 {
                     {"--axis", "", "x|y|z", "x y z", std::string(1, char('x' + so.axis)), "the axis the plane is across"},
                     {"--at", "", "V", "", fmt::format("{}", so.at), "where the plane cuts that axis"},
                     {"--output", "-o", "OUT", "FILE", "", "the picture; - is standard output (needs --format)"},
                     {"--format", "", "F", kImageFormats, "", "the image format of standard output (-o -)"},
                     {"--range", "", "UMIN,UMAX,VMIN,VMAX", "", "the scene's bounds", "the part of the plane shown"},
                     {"--width", "", "W", "", fmt::format("{}", so.width), "picture width in pixels"},
                     {"--height", "", "H", "", "from the range's aspect", "picture height in pixels"},
                     time,
                 },
                 "", true});
    c.push_back({"mesh", "SCENE -o OUT.stl|obj|ply|3mf", "a closed, sharp-edged triangle mesh (dual contouring)",
                 {
                     {"--output", "-o", "OUT", "FILE", "",
                      "the mesh: .stl, .obj, .ply or .3mf (OBJ, PLY and 3MF carry the materials' colours); - is standard output "
                      "(needs --format)"},
                     {"--format", "", "F", "stl obj ply 3mf", "", "the mesh format of standard output (-o -)"},
                     {"--resolution", "", "N", "", fmt::format("{}", m.resolution), "cells along the longest side of the box"},
                     {"--cell", "", "SIZE", "", "", "the cell size instead of --resolution"},
                     {"--bounds", "", "X0,Y0,Z0,X1,Y1,Z1", "", "found from the scene", "the box meshed (the solid is cut by it)"},
                     {"--simplify", "", "TOL", "", "", "fewer triangles, checked to stay within TOL of the surface"},
                     time,
                     threads,
                     {"--max-triangles", "", "N", "", fmt::format("{}", m.max_triangles), "refuse meshes with more triangles"},
                     {"--max-cells", "", "N", "", "2147483648", "refuse grids with more cells"},
                     {"--error", "", "", "", "",
                      "print |distance| / |gradient| at the vertices and the triangles' centroids, in cells"},
                     quiet,
                 },
                 "", true});
    c.push_back({"merge", "PART.exr... -o OUT", "put the bands of render --tiles together: the picture one render makes",
                 {
                     {"--output", "-o", "OUT", "FILE", "", "the picture (any format render writes); - is standard output (needs --format)"},
                     {"--format", "", "F", kImageFormats, "", "the image format of standard output (-o -)"},
                     quiet,
                 },
                 "The bands may come in any order; together they must cover the picture's rows once.", false});
    c.push_back({"bench", "SCENE", "time renders of the scene",
                 with({
                          {"--repeat", "", "N", "", "5", "renders timed"},
                          {"--warmup", "", "N", "", "2", "untimed renders first (their one-time costs: fresh memory, thread start-up)"},
                          threads,
                          baseline,
                          {"--fresh-tree", "", "", "", "",
                           "every render builds its own tape tree (one picture's cost), instead of taking the one the render before kept, as the frames of an animation do"},
                      },
                      render_settings()),
                 "Prints median_ms, min_ms (of the timed renders), cold_ms (the process's first render), evals_per_pixel (SDF evaluations: rays, normals, shadows, ao), shading (material "
                 "evaluations), the mean program length run (tape=MEAN/FULL), the tape tree (tree_reused=1: kept from the render before) and the kernels' instruction set (isa).",
                 true});
    c.push_back({"watch", "[--runs N] [--debounce MS] CMD ARGS...", "run a command again on every save of its scene or an import",
                 {
                     {"--runs", "", "N", "", "until Ctrl-C", "stop after N runs"},
                     {"--debounce", "", "MS", "", "100", "wait this long after the last save"},
                 },
                 "CMD is render, glsl, check, slice, mesh, eval or compile, with its own options. A failed run prints its "
                 "errors and writes nothing, so the last good output stays. One line per run on standard error.",
                 false});
    c.push_back({"preview", "SCENE", "a live WebGL2 preview in the browser, updated on every save",
                 {
                     {"--port", "", "N", "", "8421", "the port on 127.0.0.1 (0: any free port; the URL is printed)"},
                     {"--host", "", "ADDR", "", "127.0.0.1", "the address to serve on"},
                     {"--debounce", "", "MS", "", "100", "wait this long after the last save"},
                 },
                 "Open the printed URL. Each save of the scene or a file it imports sends the new shader to the page, which "
                 "keeps its camera, time and resolution; a script error shows on the page over the last good picture. Ctrl-C "
                 "stops it.",
                 true});
    c.push_back({"help", "[CMD | --man | --completion bash|zsh]", "this help, a command's, the man page, or shell completions",
                 {
                     {"--man", "", "", "", "", "the man page (roff): sdfc help --man > sdfc.1"},
                     {"--completion", "", "bash|zsh", "bash zsh", "", "the completion script for that shell"},
                 },
                 "", false});
    return c;
}

}  // namespace

const std::vector<Option>& scene_options() {
    static const std::vector<Option> opts = [] {
        const Limits l;
        auto lim = [](const char* name, auto def, const char* help) { return Option{name, "", "N", "", fmt::format("{}", def), help}; };
        return std::vector<Option>{
            {"-D", "", "NAME=VALUE", "", "",
             "the script's top-level `let NAME` takes VALUE (an expression: -D size=2, -D 'tint=[1, 0, 0]'), as OpenSCAD's -D"},
            lim("--max-recursion", l.max_recursion, "nested def calls"),
            lim("--max-iterations", l.max_loop_iterations, "iterations of one for"),
            lim("--max-calls", l.max_calls, "calls, field bodies and shapes applied to points, all together"),
            lim("--max-shapes", l.max_shapes, "shapes built"),
            lim("--max-shape-depth", l.max_shape_depth, "depth of the shape tree"),
            lim("--max-list", l.max_list, "elements of one list"),
            lim("--max-ops", l.max_ops, "IR nodes"),
            Option{"--max-file-size", "", "BYTES", "", fmt::format("{}", l.max_file_bytes), "bytes of one source file"},
            lim("--max-nesting", l.max_nesting, "syntax nesting; a modifier and its block count 2"),
            lim("--max-pixels", 268435456, "width * height * samples (of one band: --tiles)"),
            lim("--max-frames", 100000, "frames of one --frames range"),
        };
    }();
    return opts;
}

const std::vector<CommandSpec>& commands() {
    static const std::vector<CommandSpec> all = make_commands();
    return all;
}

const CommandSpec* find_command(const std::string& name) {
    for (const CommandSpec& c : commands())
        if (c.name == name) return &c;
    return nullptr;
}

std::vector<std::string> option_names(const CommandSpec& cmd) {
    std::vector<std::string> out{"--help", "-h"};
    auto add = [&](const std::vector<Option>& opts) {
        for (const Option& o : opts) {
            out.push_back(o.name);
            if (!o.alt.empty()) out.push_back(o.alt);
        }
    };
    add(cmd.options);
    if (cmd.scene_options) add(scene_options());
    return out;
}

}  // namespace sdfc::cli
