// The GLSL backend. Layout of every target's shader:
//
//   header comment (what it is, how to use it, the uniforms)
//   render settings as constants          SDF_MAX_STEPS, SDF_EPSILON, ... (render(...) of the script)
//   the per-ray rules                     compiler/render/rules.h as GLSL (shared_rules.cpp)
//   kRendererHead                         struct Material, struct SdfLight, setting globals (head.glsl)
//   sdf_noise (only if the scene uses it) kGlslNoise, compiler/ir/noise.glsl
//   sdf_powf, sdf_atan2 (if used)         kGlslPow, compiler/ir/pow.glsl
//   float map(vec3 p)                     the distance program (compiler/bytecode/codegen.cpp)
//   Material sdf_material(vec3 p)         the 11 material channels
//   void sdf_settings()                   camera, lights, ambient, background (may use sdf_time)
//   kRendererBody                         the shader's scheduling around the shared rules (camera.glsl,
//                                         marching.glsl, trace.glsl; see glsl_renderer.hpp)
//   the target's entry point              mainImage / main
//
// The three scene functions are generated from register Programs made by the same codegen as
// the VM's, one instruction at a time through opcodes.def's GLSL templates (glsl_emit.cpp).
#include "compiler/glsl/glsl.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>

#include <fmt/format.h>

#include "compiler/bytecode/compile.hpp"
#include "compiler/render/plan.hpp"
#include "compiler/glsl/glsl_emit.hpp"
#include "compiler/glsl/glsl_html.hpp"
#include "compiler/glsl/glsl_renderer.hpp"
#include "compiler/glsl/glsl_tape.hpp"
#include "compiler/scene/lower.hpp"

namespace sdfc {
namespace {

using glsl::literal;

std::string vec3_lit(float x, float y, float z) {
    return fmt::format("vec3({}, {}, {})", literal(x), literal(y), literal(z));
}

// The script's name, for the header comment.
// The script's file name, as it is (`raw`, for the html page's title: UTF-8 when the name
// is) or fit for a GLSL comment (ASCII).
std::string script_name(const Scene& s, bool raw = false) {
    auto fit = [&](const std::string& path) {
        const std::string name = std::filesystem::path(path).filename().string();
        size_t bad = 0;
        return raw && valid_utf8(name, bad) ? name : glsl::comment_text(name);
    };
    for (Loc l : {s.root ? s.root->loc : Loc{}, s.camera.loc, s.render.loc})
        if (l.file) return fit(l.file->path);
    for (const LightSettings& l : s.lights)
        if (l.loc.file) return fit(l.loc.file->path);
    return "scene";
}

glm::vec3 const3(const Graph& g, const Vec3N& v, glm::vec3 dflt) {
    glm::vec3 r = dflt;
    for (int i = 0; i < 3; ++i)
        if (v[i] != kNoNode && g.is_const(v[i])) r[i] = g.const_value(v[i]);
    return r;
}

struct Parts {
    std::string name;       // script file name (for a GLSL comment)
    std::string title;      // ... as it is (the html page's)
    std::string code;       // everything but the entry point (no #version, no uniforms)
    bool uses_time = false;
    bool tape = false;
    std::vector<uint32_t> tape_words;
    size_t tape_texels = 0;  // uvec4s of the tape
    size_t instructions = 0;
    int samples = 1, max_steps = 256, max_bounces = 3;  // the knobs (knob_block)
    std::vector<SceneParam> params;                    // the script's params (sdf_param[i])
    Program distance;                                  // (GlslOutput::distance)
    std::vector<glm::vec3> probes;                     // (GlslOutput::probes)
};

Parts generate(const Scene& scene, const GlslOptions& options, glsl::TapeStorage storage) {
    const FieldSampler sample = options.sample;
    Graph& g = *scene.graph;
    const Loc saved = g.loc();
    g.set_loc(Loc{});  // nodes made outside any shape (the scene's final scaling) name no line
    LoweredScene ls = lower_scene(g, scene);
    Program dist = codegen(g, {ls.distance}, {"d"});
    std::vector<NodeId> mroots(ls.material.begin(), ls.material.end());
    std::vector<std::string> mnames;
    for (const MatChannelInfo& ch : kMatChannelInfo) mnames.push_back(ch.output);
    Program mat = codegen(g, mroots, mnames);

    // Settings as one more program (constants unless they depend on time).
    auto node = [&](NodeId n, float dflt) { return n == kNoNode ? g.constant(dflt) : n; };
    const CameraSettings& cam = scene.camera;
    std::vector<NodeId> sroots;
    auto push3 = [&](const Vec3N& v, glm::vec3 d) {
        for (int i = 0; i < 3; ++i) sroots.push_back(node(v[i], d[i]));
    };
    push3(cam.position, {0, 0, 5});
    push3(cam.target, {0, 0, 0});
    push3(cam.up, {0, 1, 0});
    sroots.push_back(node(cam.fov, 45.0f));
    sroots.push_back(node(cam.ortho_height, 2.0f));
    push3(scene.ambient, glm::vec3(0.05f));
    push3(scene.background, glm::vec3(0.0f));
    for (const LightSettings& l : scene.lights) {
        if (l.directional) push3(l.direction, {0, -1, 0});
        else push3(l.position, {0, 0, 0});
        push3(l.color, {1, 1, 1});
        sroots.push_back(node(l.intensity, 1.0f));
        sroots.push_back(node(l.radius, 0.0f));
    }
    Program set = codegen(g, sroots, {});
    g.set_loc(saved);

    // The settings, resolved as for the CPU (compiler/render/plan.cpp): only what is
    // constant is known here (the camera may depend on time).
    PlanInputs in;
    in.settings = scene.render;
    in.bounds = scene_bounds(scene);
    in.is_2d = scene.is_2d;
    in.raw_field = scene.raw_field;
    in.has_distance = !dist.outputs.empty();
    auto const_point = [&](const Vec3N& v) -> std::optional<glm::vec3> {
        for (NodeId n : v)
            if (n != kNoNode && !g.is_const(n)) return std::nullopt;
        return const3(g, v, {0, 0, 0});
    };
    in.camera_position = cam.position[0] == kNoNode ? std::optional<glm::vec3>(glm::vec3(0, 0, 5)) : const_point(cam.position);
    in.camera_target = cam.target[0] == kNoNode ? std::optional<glm::vec3>(glm::vec3(0)) : const_point(cam.target);
    in.field = [&dist, sample](const float* x, const float* y, const float* z, size_t n, float* out) {
        sample(dist, x, y, z, n, 0.0f, out);
    };
    const RenderPlan plan = resolve_plan(in);
    const int nlights = scene.lights.empty() ? 2 : static_cast<int>(scene.lights.size());

    Parts out;
    out.name = script_name(scene);
    out.title = script_name(scene, true);
    out.uses_time = dist.uses_time || mat.uses_time || set.uses_time;
    std::string& c = out.code;
    c += fmt::format(
        "// ---- render settings (the script's render(...)) ----\n"
        "const float SDF_MAX_DIST = {};\n"
        "const float SDF_EPSILON = {};\n"
        "const bool SDF_SHADOWS = {};\n"
        "const bool SDF_AO = {};  // ambient occlusion\n"
        "const bool SDF_CONE = {};  // cone-traced anti-aliasing (render(aa = \"cone\"))\n"
        "const bool SDF_2D = {};  // a 2D model: the Prospero image\n"
        "const bool SDF_ORTHO = {};  // orthographic camera\n"
        "const float SDF_EXPOSURE = {};\n"
        "const int SDF_TONEMAP = {};  // 0 none, 1 Reinhard, 2 ACES\n",
        literal(plan.max_dist), literal(plan.eps), plan.shadows ? "true" : "false", plan.ao ? "true" : "false",
        plan.cone ? "true" : "false", plan.is_2d ? "true" : "false", cam.orthographic ? "true" : "false",
        literal(plan.exposure), plan.tonemap);
    // A sample's weight, and the least a secondary ray may carry (compiler/render/plan.cpp).
    c += "#define SDF_SAMPLE_WEIGHT (1.0 / float(SDF_SAMPLES))\n#define SDF_MIN_WEIGHT (1e-3 / float(SDF_SAMPLES))\n";
    out.samples = plan.samples;
    out.max_steps = plan.max_steps;
    out.max_bounces = plan.max_bounces;
    out.params = scene.params;
    c += fmt::format("const bool SDF_CLIP = {};  // rays are clipped to the scene's bounding box\n", plan.clip ? "true" : "false");
    c += fmt::format("const vec3 SDF_LO = {};\nconst vec3 SDF_HI = {};\n", vec3_lit(plan.lo.x, plan.lo.y, plan.lo.z),
                     vec3_lit(plan.hi.x, plan.hi.y, plan.hi.z));
    // Floor planes: rays are clipped to the hull of their parts under a plane or in the box
    // of everything else (as on the CPU).
    const size_t nplanes = plan.planes.size();
    c += fmt::format("const int SDF_NUM_PLANES = {};  // floor planes n.p <= w clipping rays, with the box below\n", nplanes);
    c += fmt::format("const vec4 SDF_PLANES[{}] = vec4[{}](", std::max<size_t>(nplanes, 1), std::max<size_t>(nplanes, 1));
    for (size_t i = 0; i < nplanes; ++i) {
        const glm::vec4& q = plan.planes[i];
        c += fmt::format("{}vec4({}, {}, {}, {})", i ? ", " : "", literal(q.x), literal(q.y), literal(q.z), literal(q.w));
    }
    if (nplanes == 0) c += "vec4(0.0)";
    c += ");\n";
    c += fmt::format("const vec3 SDF_SOLID_LO = {};\nconst vec3 SDF_SOLID_HI = {};\n", vec3_lit(plan.solid_lo.x, plan.solid_lo.y, plan.solid_lo.z),
                     vec3_lit(plan.solid_hi.x, plan.solid_hi.y, plan.solid_hi.z));
    c += fmt::format("const float SDF_RELAX = {};  // over-relaxed sphere tracing\n", literal(plan.relax));
    c += fmt::format("const bool SDF_PREMARCH = {};  // primary rays start where their tile's cone march ends\n",
                     plan.premarch ? "true" : "false");
    c += fmt::format("const bool SDF_RAW = {};  // a raw field (.vm model): no distance bound, sign-change marching\n"
                     "const float SDF_RAW_INV_LIPSCHITZ = {};\nconst float SDF_RAW_MAX_STEP = {};\n",
                     plan.raw ? "true" : "false", literal(1.0f / plan.raw_lipschitz), literal(plan.raw_max_step));
    c += fmt::format("const int SDF_NUM_LIGHTS = {};\nconst bool SDF_DEFAULT_LIGHTS = {};  // the script has no light: the default rig\n\n",
                     nlights, scene.lights.empty() ? "true" : "false");
    c += "\n// ---- the per-ray rules both renderers share (compiler/render/rules.h) ----\n";
    c += glsl::shared_rules_glsl(glsl::kSharedRules);
    c += "\n";
    c += glsl::kRendererHead;
    c += glsl::op_helpers({&dist, &mat, &set});

    out.instructions = dist.code.size() + mat.code.size();
    out.tape = options.code == GlslCode::Tape || (options.code == GlslCode::Auto && out.instructions >= kTapeThreshold);
    glsl::FunctionSpec fs;
    if (scene.root->kind == ShapeKind::Union) fs.quiet = scene.root->loc;
    auto material_return = [](const std::vector<std::string>& o) {
        // Channels that are not a plain name or number get a named local, for readability.
        std::vector<std::string> lines, v(o.begin(), o.end());
        for (int i = 0; i < kMatChannels; ++i)
            if (v[i].find_first_of(" (") != std::string::npos) {
                lines.push_back(fmt::format("float {} = {};", kMatChannelInfo[i].glsl, v[i]));
                v[i] = kMatChannelInfo[i].glsl;
            }
        lines.push_back(fmt::format("return Material(vec3({}, {}, {}), {}, {}, {}, {}, {}, vec3({}, {}, {}));", v[0], v[1], v[2], v[3], v[4],
                                    v[5], v[6], v[7], v[8], v[9], v[10]));
        return lines;
    };
    if (out.tape) {
        // The programs as data (compiler/glsl/glsl_tape.hpp): the shader's code does not grow
        // with the scene.
        const glsl::PackedTapes t = glsl::pack_tapes({&dist, &mat});
        c += "\n";
        c += glsl::tape_interpreter(t, storage);
        const glsl::TapeSegment &sd = t.segments[0], &sm = t.segments[1];
        auto reg = [](uint16_t r) { return fmt::format("sdf_reg[{}]", r); };
        c += fmt::format(
            "\n// ---- the scene's distance (a safe bound: 1-Lipschitz): {} instructions of the tape ----\n"
            "float map(vec3 p) {{\n    sdf_run({}, {}, p);\n    return {};\n}}\n",
            dist.code.size(), sd.begin, sd.end, reg(sd.outputs[0]));
        std::vector<std::string> o;
        for (uint16_t r : sm.outputs) o.push_back(reg(r));
        c += fmt::format(
            "\n// ---- materials: colour, specular, shininess, reflectance, transparency, ior, emission: {} instructions of the tape ----\n"
            "Material sdf_material(vec3 p) {{\n    sdf_run({}, {}, p);\n",
            mat.code.size(), sm.begin, sm.end);
        for (const std::string& line : material_return(o)) c += "    " + line + "\n";
        c += "}\n";
        out.tape_texels = t.words.size() / 4;
        if (storage == glsl::TapeStorage::Texture) out.tape_words = t.words;
    } else {
        fs.signature = "float map(vec3 p)";
        fs.var_prefix = "d";
        c += "\n// ---- the scene's distance (a safe bound: 1-Lipschitz) ----\n";
        c += glsl::function(dist, fs);
        fs.signature = "Material sdf_material(vec3 p)";
        fs.var_prefix = "m";
        fs.finish = material_return;
        c += "\n// ---- materials: colour, specular, shininess, reflectance, transparency, ior, emission ----\n";
        c += glsl::function(mat, fs);
    }

    fs.signature = "void sdf_settings()";
    fs.var_prefix = "s";
    const std::vector<LightSettings>& lights = scene.lights;
    fs.finish = [&lights](const std::vector<std::string>& o) {
        std::vector<std::string> l;
        auto v3 = [&](size_t i) { return fmt::format("vec3({}, {}, {})", o[i], o[i + 1], o[i + 2]); };
        l.push_back("sdf_cam_position = " + v3(0) + ";");
        l.push_back("sdf_cam_target = " + v3(3) + ";");
        l.push_back("sdf_cam_up = " + v3(6) + ";");
        l.push_back("sdf_cam_fov = " + o[9] + ";  // vertical, degrees");
        l.push_back("sdf_cam_ortho_height = " + o[10] + ";");
        l.push_back("sdf_ambient = " + v3(11) + ";");
        l.push_back("sdf_background = " + v3(14) + ";");
        if (lights.empty()) {
            // The default rig (compiler/render/rules.h, as compiler/render/plan.cpp makes it).
            l.push_back("vec3 fwd = normalize(sdf_cam_target - sdf_cam_position);");
            l.push_back("vec3 right = normalize(cross(fwd, sdf_cam_up));");
            l.push_back("vec3 up = normalize(sdf_cam_up);");
            l.push_back("sdf_lights[0] = SdfLight(true, vec3(0.0), sdf_key_light_dir(fwd, right, up), sdf_key_light_color(), sdf_key_light_intensity(), 0.0);");
            l.push_back("sdf_lights[1] = SdfLight(true, vec3(0.0), sdf_fill_light_dir(fwd, right, up), sdf_fill_light_color(), sdf_fill_light_intensity(), 0.0);");
        }
        for (size_t i = 0; i < lights.size(); ++i) {
            const size_t b = 17 + 8 * i;
            const std::string ln = lights[i].loc.known() ? fmt::format("  // line {}", lights[i].loc.line) : "";
            if (lights[i].directional)
                l.push_back(fmt::format("sdf_lights[{}] = SdfLight(true, vec3(0.0), {}, {}, {}, {});{}", i, v3(b), v3(b + 3), o[b + 6], o[b + 7], ln));
            else
                l.push_back(fmt::format("sdf_lights[{}] = SdfLight(false, {}, vec3(0.0, -1.0, 0.0), {}, {}, {});{}", i, v3(b), v3(b + 3), o[b + 6],
                                        o[b + 7], ln));
        }
        return l;
    };
    c += "\n// ---- scene settings: camera, lights, ambient, background ----\n";
    c += glsl::function(set, fs);
    c += glsl::kRendererBody;
    out.probes.push_back(glm::vec3(0.0f));
    if (in.camera_position) out.probes.push_back(*in.camera_position);
    if (in.camera_target) out.probes.push_back(*in.camera_target);
    out.distance = std::move(dist);
    return out;
}

std::string header(const Parts& p, const char* target_line) {
    return fmt::format("// Generated by sdfc from {}.\n{}", p.name, target_line);
}

// What the html page needs to know of the scene besides its shader: whether time matters,
// the knobs' values for the script.
std::string scene_json(const Parts& p) {
    std::string params;
    for (size_t i = 0; i < p.params.size(); ++i) {
        const SceneParam& q = p.params[i];
        params += fmt::format("{}{{\"name\":\"{}\",\"value\":{},\"min\":{},\"max\":{},\"step\":{},\"uniform\":\"sdf_param[{}]\"}}", i ? "," : "",
                              q.name, q.value, q.min, q.max, q.step, i);
    }
    return fmt::format("{{\"uses_time\":{},\"samples\":{},\"max_steps\":{},\"max_bounces\":{},\"params\":[{}]}}",
                       p.uses_time ? "true" : "false", p.samples, p.max_steps, p.max_bounces, params);
}

// The script's params: uniforms the page's sliders set, or #defines at the top of a pasted
// shader (a param's line names it in the script).
// GLSL reserves names with "__" (SDF_PARAM__r for a param `_r`): those get their index and
// single underscores, and the script's name stays in the comment.
std::string param_define(const std::string& name, size_t i) {
    if (name.find("__") == std::string::npos && name.front() != '_') return "SDF_PARAM_" + name;
    std::string clean;
    for (char c : name)
        if (c != '_' || (!clean.empty() && clean.back() != '_')) clean += c;
    while (!clean.empty() && clean.back() == '_') clean.pop_back();
    return fmt::format("SDF_PARAM_{}{}{}", i, clean.empty() ? "" : "_", clean);
}

std::string param_block(const Parts& p, bool uniforms) {
    const size_t n = p.params.size();
    if (n == 0) return "";
    if (uniforms) return fmt::format("uniform float sdf_param[{}];  // the script's params (the page's sliders)\n", n);
    std::string s = "// ---- the script's params (let NAME = param(...)): edit these ----\n";
    std::string list;
    for (size_t i = 0; i < n; ++i) {
        const SceneParam& q = p.params[i];
        const std::string define = param_define(q.name, i);
        const std::string own = define == "SDF_PARAM_" + q.name ? "" : fmt::format("{} ", q.name);
        s += fmt::format("#define {} {}  // {}in [{}, {}]; line {}\n", define, literal(q.value), own, literal(q.min), literal(q.max),
                         q.loc.line);
        list += fmt::format("{}{}", i ? ", " : "", define);
    }
    s += fmt::format("const float sdf_param[{}] = float[{}]({});\n\n", n, n, list);
    return s;
}

// The settings a user turns while looking: #defines at the top of a pasted shader, uniforms
// the html page sets (its controls; the stack of rays is sized for kPageBounceCap bounces).
constexpr int kPageBounceCap = 8;
std::string knob_block(const Parts& p, GlslTarget target) {
    if (target == GlslTarget::Html || target == GlslTarget::HtmlShader)
        return fmt::format(
            "uniform int uSamples;     // samples per pixel (the page's control; script: {})\n"
            "uniform int uMaxSteps;    // sphere-tracing steps a ray (script: {})\n"
            "uniform int uMaxBounces;  // mirror and glass bounces (script: {})\n"
            "const int SDF_BOUNCE_CAP = {};\n"
            "#define SDF_SAMPLES (SDF_CONE ? 1 : max(uSamples, 1))\n"
            "#define SDF_MAX_STEPS uMaxSteps\n"
            "#define SDF_MAX_BOUNCES min(uMaxBounces, SDF_BOUNCE_CAP)\n{}",
            p.samples, p.max_steps, p.max_bounces, std::max(kPageBounceCap, p.max_bounces), param_block(p, true));
    return fmt::format(
        "// ---- knobs: edit these (sdfc glsl --samples N --max-steps N --max-bounces N sets them) ----\n"
        "#define SDF_SAMPLES {:<8}// samples per pixel (anti-aliasing; 1 with render(aa = \"cone\"))\n"
        "#define SDF_MAX_STEPS {:<6}// sphere-tracing steps a ray\n"
        "#define SDF_MAX_BOUNCES {:<4}// mirror and glass bounces\n"
        "#define SDF_BOUNCE_CAP SDF_MAX_BOUNCES\n\n{}",
        p.samples, p.max_steps, p.max_bounces, param_block(p, false));
}

}  // namespace

namespace {

std::string target_text(const Parts& p, GlslTarget target) {
    switch (target) {
        case GlslTarget::Shadertoy: {
            std::string s = header(p,
                                   "// Shadertoy: paste into a new shader's Image tab on shadertoy.com. The script's `time` is\n"
                                   "// iTime; drag with the mouse to orbit the camera around its target (release: the\n"
                                   "// script's camera). The picture matches `sdfc render` (same camera, tracing and shading).\n\n");
            s += knob_block(p, target);
            s += p.code;
            s += "\nvoid mainImage(out vec4 fragColor, in vec2 fragCoord) {\n"
                 "    fragColor = sdf_render(fragCoord, iResolution.xy, iTime, sdf_mouse_orbit(iMouse, iResolution.xy), vec2(0.0));\n"
                 "}\n";
            return s;
        }
        case GlslTarget::Glsl330: {
            std::string s = "#version 330 core\n";
            s += header(p,
                        "// A desktop OpenGL 3.3 fragment shader. Draw a full-screen triangle (any vertex shader\n"
                        "// that covers the viewport) and set these uniforms:\n"
                        "//   iResolution  viewport size in pixels\n"
                        "//   iTime        scene time in seconds (the script's `time`)\n"
                        "//   iMouse       Shadertoy's convention: xy = pointer position in pixels (origin at\n"
                        "//                the bottom left), zw = where the button went down, z > 0 while pressed;\n"
                        "//                while pressed, dragging orbits the camera; all zero: the script's camera.\n"
                        "// fragColor is display-ready (sRGB-encoded) colour; write it to an 8-bit framebuffer\n"
                        "// without GL_FRAMEBUFFER_SRGB.\n\n");
            // Shadertoy's names (LANGUAGE.md: `time` becomes iTime in GLSL).
            if (!p.tape_words.empty())
                s += fmt::format(
                    "// The scene's programs are a tape in a texture: upload the words of `sdfc glsl --tape-file`\n"
                    "// (little-endian uint32, {} texels) as an RGBA32UI texture {} texels wide and {} high\n"
                    "// (GL_RGBA_INTEGER, GL_UNSIGNED_INT, GL_NEAREST filters) and bind it to sdf_tape.\n\n",
                    p.tape_words.size() / 4, glsl::kTapeTextureWidth, glsl::tape_texture_rows(p.tape_words.size() / 4));
            s += "uniform vec2 iResolution;\nuniform float iTime;\nuniform vec4 iMouse;\nout vec4 fragColor;\n\n";
            s += knob_block(p, target);
            s += p.code;
            s += "\nvoid main() {\n"
                 "    fragColor = sdf_render(gl_FragCoord.xy, iResolution, iTime, sdf_mouse_orbit(iMouse, iResolution), vec2(0.0));\n"
                 "}\n";
            return s;
        }
        case GlslTarget::Html:
        case GlslTarget::HtmlShader: {
            std::string s = "#version 300 es\n";
            s += header(p, "// WebGL2 preview shader (GLSL ES 3.00): the Shadertoy code with its knobs and the page's camera as uniforms.\n\n");
            s += "precision highp float;\nprecision highp int;\nprecision highp sampler2D;\n"
                 "uniform vec3 iResolution;\nuniform float iTime;\nuniform vec4 iMouse;\n"
                 "uniform vec4 uOrbit;  // yaw, pitch (radians), zoom, on\n"
                 "uniform vec2 uPan;    // target offset in the view plane, in units of the orbit radius\n"
                 "out vec4 sdf_frag_color;\n";
            s += knob_block(p, target);
            s += "\n";
            s += p.code;
            s += "\n";
            s += glsl::kPageMain;
            if (target == GlslTarget::HtmlShader) return s;
            return glsl::html_page(p.title, s, scene_json(p), false, p.tape_words);
        }
    }
    return {};
}

}  // namespace

GlslOutput compile_glsl(const Scene& scene, GlslTarget target, const GlslOptions& options) {
    if (!scene.graph || !scene.root) throw CompileError(Loc{}, "internal: the scene has no graph");
    const bool page = target == GlslTarget::Html || target == GlslTarget::HtmlShader;
    const bool texture = page || (target == GlslTarget::Glsl330 && options.tape_texture);
    Parts p = generate(scene, options, texture ? glsl::TapeStorage::Texture : glsl::TapeStorage::ConstArray);
    GlslOutput out;
    out.text = target_text(p, target);
    out.uses_time = p.uses_time;
    out.tape = p.tape;
    out.tape_texels = p.tape_texels;
    out.instructions = p.instructions;
    out.samples = p.samples;
    out.max_steps = p.max_steps;
    out.max_bounces = p.max_bounces;
    out.scene_json = scene_json(p);
    out.distance = std::move(p.distance);
    out.probes = std::move(p.probes);
    if (target == GlslTarget::HtmlShader || target == GlslTarget::Glsl330) out.tape_words = std::move(p.tape_words);
    return out;
}

std::string emit_glsl(const Scene& scene, GlslTarget target, FieldSampler sample, bool* uses_time) {
    GlslOptions o;
    o.sample = sample;
    GlslOutput out = compile_glsl(scene, target, o);
    if (uses_time) *uses_time = out.uses_time;
    return std::move(out.text);
}

std::string html_live_page(const std::string& title) { return glsl::html_page(title, "", "", true); }

}  // namespace sdfc
