// The public API (sdfc.hpp) over the stages: lang (script -> Scene), compiler/bytecode
// (Scene -> programs), runtime/cpu (pictures), compiler/glsl, runtime/mesh. A compiled
// scene keeps its sources alive (diagnostics and locations point into them).
#include "runtime/api/sdfc.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "compiler/bytecode/compile.hpp"
#include "compiler/glsl/glsl.hpp"
#include "lang/load.hpp"
#include "runtime/cpu/slice.hpp"
#include "runtime/cpu/tracer.hpp"
#include "runtime/eval/vm.hpp"
#include "runtime/io/image.hpp"
#include "runtime/mesh/mesh.hpp"
#include "runtime/mesh/mesh_file.hpp"

#ifndef SDFC_VERSION
#define SDFC_VERSION "0.0.0"
#endif

namespace sdfc::api {

struct Scene::Impl {
    std::unique_ptr<SourceManager> sources = std::make_unique<SourceManager>();
    std::optional<std::string> text;  // compile_string's text (else `path` is read)
    std::string path;
    Options options;
    std::vector<Diagnostic> diagnostics;
    bool ok = false;
    sdfc::Scene scene;
    CompiledScene compiled;
    std::unique_ptr<Raster2d> raster;  // a 2D model, prepared once for every render
};

namespace {

Diagnostic convert(const sdfc::Diagnostic& d, const char* severity) {
    Diagnostic o;
    if (d.loc.file) o.file = d.loc.file->path;
    o.line = int(d.loc.line);
    o.column = int(d.loc.col);
    o.severity = severity;
    o.message = d.message;
    o.text = format_diagnostic(d, severity);
    return o;
}

InterpretOptions interpret_options(const Options& o, std::optional<float> time) {
    InterpretOptions io;
    io.time = time;
    for (const auto& [name, value] : o.defines) io.defines.push_back({name, value});
    return io;
}

// The script as the interpreter sees it, read into `sm` (a file, or the text given).
sdfc::Scene interpret(SourceManager& sm, const Scene::Impl& s, std::optional<float> time) {
    const InterpretOptions io = interpret_options(s.options, time);
    if (s.text) return interpret_source(sm, sm.add(s.path, *s.text), io);
    return load_scene(sm, s.path, io);
}

std::shared_ptr<Scene::Impl> compile(std::shared_ptr<Scene::Impl> s) {
    try {
        s->scene = interpret(*s->sources, *s, s->options.time);
        for (const sdfc::Diagnostic& w : s->scene.warnings) s->diagnostics.push_back(convert(w, "warning"));
        s->compiled = compile_scene(s->scene);
        if (s->compiled.is_2d && !s->compiled.distance.outputs.empty()) s->raster = std::make_unique<Raster2d>(s->compiled);
        s->ok = true;
    } catch (const CompileError& e) {
        for (const sdfc::Diagnostic& d : e.diagnostics()) s->diagnostics.push_back(convert(d, "error"));
    } catch (const DefineError& e) {
        s->diagnostics.push_back({s->path, 0, 0, "error", e.what(), std::string("sdfc: error: ") + e.what() + "\n"});
    } catch (const std::exception& e) {  // a file that cannot be opened, a limit of the system
        s->diagnostics.push_back({s->path, 0, 0, "error", e.what(), std::string("sdfc: error: ") + e.what() + "\n"});
    }
    return s;
}

std::string summary(const std::vector<Diagnostic>& ds) {
    for (const Diagnostic& d : ds)
        if (d.severity == "error") return d.text;
    return "the scene did not compile";
}

}  // namespace

Error::Error(const std::string& what, std::vector<Diagnostic> diagnostics)
    : std::runtime_error(what), diagnostics_(std::move(diagnostics)) {}

std::vector<std::uint8_t> Image::srgb8() const {
    const size_t n = rgb.size() / 3, k = alpha.empty() ? 3 : 4;
    auto byte = [](float v) { return std::uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
    std::vector<std::uint8_t> out(n * k);
    for (size_t p = 0; p < n; ++p) {
        const float a = k == 4 ? alpha[p] : 1.0f;
        for (size_t c = 0; c < 3; ++c) out[p * k + c] = byte(linear_to_srgb(k == 4 ? (a > 0.0f ? rgb[p * 3 + c] / a : 0.0f) : rgb[p * 3 + c]));
        if (k == 4) out[p * k + 3] = byte(a);
    }
    return out;
}

Scene::Scene() : impl_(std::make_shared<Impl>()) {}
Scene::Scene(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

bool Scene::ok() const { return impl_->ok; }
const std::vector<Diagnostic>& Scene::diagnostics() const { return impl_->diagnostics; }

const Scene::Impl& Scene::compiled() const {
    if (!impl_->ok) throw Error(summary(impl_->diagnostics), impl_->diagnostics);
    return *impl_;
}

void Scene::distances(const float* x, const float* y, const float* z, float* out, std::size_t n) const {
    const Impl& s = compiled();
    Evaluator ev(s.compiled.distance);  // scratch of this call's own: threads do not share it
    for (size_t i = 0; i < n; i += kBatch) {
        const int k = int(std::min<size_t>(kBatch, n - i));
        ev.eval(x + i, y + i, z + i, k, s.compiled.time);
        std::copy(ev.output(0), ev.output(0) + k, out + i);
    }
}

float Scene::distance(float x, float y, float z) const {
    float d = 0.0f;
    distances(&x, &y, &z, &d, 1);
    return d;
}

Image Scene::render(const RenderSettings& r) const {
    const Impl& s = compiled();
    CompiledScene cs = s.compiled;  // the settings below are this call's
    if (r.width < 0 || r.height < 0 || r.samples < 0 || r.width > 16384 || r.height > 16384 || r.samples > 4096)
        throw Error("render: width and height must be from 1 to 16384 and samples from 1 to 4096 (0: the script's)");
    // (as the command line's --threads: oneTBB's arena fails far above what it can run)
    if (r.threads < 0 || r.threads > 1024) throw Error("render: threads must be from 1 to 1024 (0: all hardware threads)");
    if (r.width) cs.render.width = r.width;
    if (r.height) cs.render.height = r.height;
    if (r.samples) cs.render.samples = r.samples;
    sdfc::Image img;
    if (cs.is_2d) {
        img = s.raster ? s.raster->render(cs.render.width, cs.render.height, r.threads)
                       : sdfc::Image(std::max(cs.render.width, 1), std::max(cs.render.height, 1), 1);  // no field: nothing inside
    } else {
        RenderOptions ro;
        ro.threads = r.threads;
        ro.alpha = r.alpha;
        img = sdfc::render(cs, ro);
    }
    Image out;
    out.width = img.width, out.height = img.height;
    out.rgb.resize(size_t(img.width) * img.height * 3);
    const bool with_alpha = r.alpha && img.channels == 4;
    if (r.alpha) out.alpha.assign(size_t(img.width) * img.height, 1.0f);  // a 2D model covers everything
    for (size_t p = 0; p < size_t(img.width) * img.height; ++p) {
        for (int c = 0; c < 3; ++c) out.rgb[p * 3 + c] = img.pixels[p * img.channels + size_t(std::min(c, std::min(img.channels, 3) - 1))];
        if (with_alpha) out.alpha[p] = img.pixels[p * 4 + 3];
    }
    return out;
}

std::string Scene::glsl(const std::string& target) const {
    const Impl& s = compiled();
    GlslTarget t;
    if (target == "shadertoy") t = GlslTarget::Shadertoy;
    else if (target == "glsl330") t = GlslTarget::Glsl330;
    else if (target == "html") t = GlslTarget::Html;
    else throw Error("glsl: the target is shadertoy, glsl330 or html, not '" + target + "'");
    SourceManager sm;
    try {
        return emit_glsl(interpret(sm, s, std::nullopt), t, sample_batch);
    } catch (const CompileError& e) {
        std::vector<Diagnostic> ds;
        for (const sdfc::Diagnostic& d : e.diagnostics()) ds.push_back(convert(d, "error"));
        throw Error(summary(ds), ds);
    }
}

Mesh Scene::mesh(const MeshSettings& m) const {
    const Impl& s = compiled();
    if (s.compiled.is_2d) throw Error("mesh: the scene is 2D (render it instead)");
    if (m.resolution < 1 || m.resolution > 16384) throw Error("mesh: the resolution must be from 1 to 16384");
    if (!(m.simplify >= 0.0f) || !std::isfinite(m.simplify)) throw Error("mesh: simplify must be 0 or a distance above 0");
    mesh::MeshOptions mo;
    mo.resolution = m.resolution;
    mo.simplify = m.simplify;
    mo.colors = m.colors;
    mo.time = s.compiled.time;
    const bool given = std::any_of(m.bounds.begin(), m.bounds.end(), [](float v) { return v != 0.0f; });
    if (given) {
        mo.lo = {m.bounds[0], m.bounds[1], m.bounds[2]}, mo.hi = {m.bounds[3], m.bounds[4], m.bounds[5]};
        if (!(mo.lo.x < mo.hi.x && mo.lo.y < mo.hi.y && mo.lo.z < mo.hi.z)) throw Error("mesh: the bounds need lo < hi on every axis");
    } else if (!mesh::default_box(s.compiled, mo.lo, mo.hi, mo.time, 8192, mo.resolution)) {
        throw Error("mesh: the scene is unbounded (a plane, an infinite repetition?): give MeshSettings::bounds");
    }
    const mesh::Mesh got = mesh::mesh_scene(s.compiled, mo);
    Mesh out;
    out.positions.reserve(got.positions.size());
    for (const auto& p : got.positions) out.positions.push_back({p.x, p.y, p.z});
    for (const auto& c : got.colors) out.colors.push_back({c.x, c.y, c.z});
    out.triangles = got.triangles;
    return out;
}

Scene compile_file(const std::string& path, const Options& options) {
    auto s = std::make_shared<Scene::Impl>();
    s->path = path;
    s->options = options;
    return Scene(compile(std::move(s)));
}

Scene compile_string(const std::string& text, const std::string& name, const Options& options) {
    auto s = std::make_shared<Scene::Impl>();
    s->path = name;
    s->text = text;
    s->options = options;
    return Scene(compile(std::move(s)));
}

void write_mesh(const Mesh& m, const std::string& path) {
    mesh::Mesh internal;
    for (const auto& p : m.positions) internal.positions.push_back({p[0], p[1], p[2]});
    for (const auto& c : m.colors) internal.colors.push_back({c[0], c[1], c[2]});
    internal.triangles = m.triangles;
    try {
        mesh::write_mesh(path, internal);
    } catch (const std::exception& e) {
        throw Error(e.what());
    }
}

const char* version() { return SDFC_VERSION; }

}  // namespace sdfc::api
