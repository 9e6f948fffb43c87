// Scene -> CompiledScene: lower both roots, generate the two programs, resolve settings.
#include "compiler/bytecode/compile.hpp"

#include <cmath>
#include <exception>
#include <future>
#include <system_error>

#include <fmt/format.h>

#include "compiler/scene/lower.hpp"

namespace sdfc {

LoweredScene lower_scene(Graph& g, const Scene& scene) {
    g.clear_guards();  // codegen takes the regions of this lowering
    Vec3N p{g.input(Op::VarX), g.input(Op::VarY), g.input(Op::VarZ)};
    LoweredScene out;
    // One pass gives both: the distance nodes are the same with or without materials.
    MaterialN base = default_material(g);
    Lowered l = lower_shape(g, *scene.root, p, &base);
    out.distance = out.shading_distance = l.lip == 1.0f ? l.d : g.mulc(l.d, 1.0f / l.lip);
    out.material = l.m;
    return out;
}

namespace {

// A plane at the top of the scene (through material modifiers): a floor.
bool is_floor(const Shape& s) {
    if (s.kind == ShapeKind::Material) return s.children.size() == 1 && is_floor(*s.children[0]);
    return s.kind == ShapeKind::Plane;
}

// The rest of a scene with floors, when its bounds are unknown (a custom field): its
// distance, for the mesher to find them with the intervals. kNoNode when not needed.
NodeId solid_without_floors(Graph& g, const Scene& scene, const SceneBounds& sb) {
    if (scene.raw_field || sb.bounds.finite() || sb.solid_bounds.finite() || scene.root->kind != ShapeKind::Union) return kNoNode;
    Vec3N p{g.input(Op::VarX), g.input(Op::VarY), g.input(Op::VarZ)};
    NodeId d = kNoNode;
    bool floors = false;
    for (const auto& c : scene.root->children) {
        if (is_floor(*c)) {
            floors = true;
            continue;
        }
        const Lowered l = lower_shape(g, *c, p, nullptr);
        const NodeId di = l.lip == 1.0f ? l.d : g.mulc(l.d, 1.0f / l.lip);
        d = d == kNoNode ? di : g.min(d, di);
    }
    return floors ? d : kNoNode;
}

float constant(const Graph& g, NodeId n, Loc loc, const char* what) {
    if (n == kNoNode) throw CompileError(loc, fmt::format("internal: {} is unset", what));
    if (!g.is_const(n)) throw CompileError(loc, fmt::format("{} must be a constant here", what));
    if (!std::isfinite(g.const_value(n))) throw CompileError(loc, fmt::format("{} is not a finite number", what));
    return g.const_value(n);
}
glm::vec3 constant3(const Graph& g, const Vec3N& v, Loc loc, const char* what) {
    return {constant(g, v[0], loc, what), constant(g, v[1], loc, what), constant(g, v[2], loc, what)};
}

// Script constants are checked as the interpreter computes them, but lowering folds more
// (a gyroid's 2*pi/period, a normal divided by its length...), which can still overflow:
// a NaN or infinite constant in a program is an error at the line that made it.
void check_constants(const Program& p) {
    for (size_t i = 0; i < p.code.size(); ++i) {
        const Instr& in = p.code[i];
        if (op_info(in.op).has_imm && !std::isfinite(in.k))
            throw CompileError(i < p.locs.size() ? p.locs[i] : Loc{},
                               fmt::format("this expression is not a finite number ({})", shown_number(in.k)));
    }
}

}  // namespace

std::string camera_problem(const ResolvedCamera& cam) {
    auto finite = [](glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    if (!finite(cam.position)) return "the camera position is not a finite number";
    if (!finite(cam.target)) return "the camera target is not a finite number";
    if (!finite(cam.up)) return "the camera up vector is not a finite number";
    // Past this a float ray origin is coarser than 1e8 units: nothing of a scene can be seen.
    constexpr float kFar = 1e15f;
    for (int i = 0; i < 3; ++i) {
        if (std::fabs(cam.position[i]) > kFar) return "the camera position is too far from the origin (at most 1e15 on each axis)";
        if (std::fabs(cam.target[i]) > kFar) return "the camera target is too far from the origin (at most 1e15 on each axis)";
    }
    // A view direction and a right vector must exist, or every ray is NaN (in double: the
    // squared length of a 1e15 view fits).
    const glm::dvec3 view = glm::dvec3(cam.target) - glm::dvec3(cam.position), up(cam.up);
    if (!(glm::length(view) > 0.0)) return "the camera's position and target are the same point";
    if (!(glm::length(up) > 0.0) || !(glm::length(glm::cross(glm::normalize(view), glm::normalize(up))) > 1e-5))
        return "the camera's up vector must not be zero or parallel to the view direction";
    return {};
}

SceneBounds scene_bounds(const Scene& scene) {
    const Graph& g = *scene.graph;
    SceneBounds out;
    out.bounds = shape_bounds(g, *scene.root);
    if (!out.bounds.finite() && !scene.raw_field) {
        Bounds box{glm::vec3(1e30f), glm::vec3(-1e30f)};
        std::vector<glm::vec4> half_spaces;
        if (clip_regions(g, *scene.root, box, half_spaces) && !half_spaces.empty()) {
            out.solid_bounds = box;
            out.half_spaces = std::move(half_spaces);
        }
    }
    return out;
}

namespace {

// The distance and shading programs only read the graph: a big scene's are made at once, on
// this thread and one more (codegen was 18 % of a 10,000-statement script's check). Errors
// come out in the order one thread would give them (the distance program's first).
constexpr size_t kParallelCodegenNodes = 20000;

void make_programs(const Graph& g, NodeId distance, const std::vector<NodeId>& roots, const std::vector<std::string>& names,
                   CompiledScene& cs) {
    std::future<Program> d;
    if (g.size() >= kParallelCodegenNodes) {
        try {
            d = std::async(std::launch::async, [&g, distance] { return codegen(g, {distance}, {"d"}); });
        } catch (const std::system_error&) {  // no thread to be had: one after the other
        }
    }
    if (!d.valid()) {
        cs.distance = codegen(g, {distance}, {"d"});
        cs.shading = codegen(g, roots, names);
        return;
    }
    std::exception_ptr shading_error;
    try {
        cs.shading = codegen(g, roots, names);
    } catch (...) {
        shading_error = std::current_exception();
    }
    cs.distance = d.get();
    if (shading_error) std::rethrow_exception(shading_error);
}

}  // namespace

bool out_of_view(const ResolvedCamera& cam, const glm::vec3& lo, const glm::vec3& hi, float aspect) {
    if (cam.orthographic) return false;
    const glm::vec3 c = cam.position;
    const glm::vec3 f = glm::normalize(cam.target - c), r = glm::normalize(glm::cross(f, cam.up)), u = glm::cross(r, f);
    const float th = std::tan(glm::radians(cam.fov) * 0.5f), tw = th * aspect;
    bool out[5] = {true, true, true, true, true};
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 p((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
        const glm::vec3 d = p - c;
        const float z = glm::dot(d, f), x = glm::dot(d, r), y = glm::dot(d, u);
        out[0] &= z <= 0.0f, out[1] &= x > z * tw, out[2] &= x < -z * tw, out[3] &= y > z * th, out[4] &= y < -z * th;
    }
    return out[0] || out[1] || out[2] || out[3] || out[4];
}

namespace {

// A script without camera() whose scene's bounding sphere holds the default camera (a model
// in millimetres, as OpenSCAD's are, around or just before a camera at [0, 0, 5]) or lies
// wholly out of its view is seen from outside instead: from the front, right and above (as
// OpenSCAD's first view), from where its bounding sphere fills the vertical field of view.
// Elsewhere the default stays (LANGUAGE.md section 8).
void frame_default_camera(CompiledScene& cs) {
    const Bounds& b = cs.bounds.finite() ? cs.bounds : cs.solid_bounds;
    if (!b.finite() || !(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) return;
    ResolvedCamera& cam = cs.camera;
    const glm::vec3 centre = 0.5f * (b.lo + b.hi);
    const float radius = 0.5f * glm::length(b.hi - b.lo);
    // Too near (within the bounds' sphere: inside them, or a 60 x 40 mm plate 4 mm away) or
    // looking away.
    const bool near = glm::length(cam.position - centre) < radius;
    if (!near && !out_of_view(cam, b.lo, b.hi, float(std::max(cs.render.width, 1)) / float(std::max(cs.render.height, 1)))) return;
    const float dist = 1.05f * radius / std::sin(glm::radians(cam.fov) * 0.5f);
    if (!std::isfinite(dist) || !(dist > 0.0f)) return;
    ResolvedCamera framed = cam;
    framed.target = centre;
    framed.position = centre + glm::normalize(glm::vec3(0.6f, 0.5f, 1.0f)) * dist;  // front, right and above
    framed.ortho_height = 2.1f * radius;
    if (camera_problem(framed).empty()) cam = framed;
}

}  // namespace

CompiledScene compile_scene(const Scene& scene) {
    Graph& g = *scene.graph;
    CompiledScene cs;
    LoweredScene ls = lower_scene(g, scene);
    std::vector<NodeId> roots{ls.shading_distance};
    std::vector<std::string> names{"d"};
    for (const MatChannelInfo& c : kMatChannelInfo) names.push_back(c.output);
    for (NodeId m : ls.material) roots.push_back(m);
    make_programs(g, ls.distance, roots, names, cs);
    check_constants(cs.distance);
    check_constants(cs.shading);

    const CameraSettings& c = scene.camera;
    cs.camera.position = constant3(g, c.position, c.loc, "the camera position");
    cs.camera.target = constant3(g, c.target, c.loc, "the camera target");
    cs.camera.up = constant3(g, c.up, c.loc, "the camera up vector");
    cs.camera.fov = constant(g, c.fov, c.loc, "the camera fov");
    cs.camera.orthographic = c.orthographic;
    cs.camera.ortho_height = constant(g, c.ortho_height, c.loc, "the camera ortho_height");
    const std::string why = camera_problem(cs.camera);
    if (!why.empty()) throw CompileError(c.loc, why);
    for (const LightSettings& l : scene.lights) {
        ResolvedLight r;
        r.directional = l.directional;
        if (l.directional) {
            glm::vec3 d = constant3(g, l.direction, l.loc, "the light direction");
            r.direction = glm::length(d) > 0 ? glm::normalize(d) : glm::vec3(0, -1, 0);
        } else {
            r.position = constant3(g, l.position, l.loc, "the light position");
        }
        r.color = constant3(g, l.color, l.loc, "the light color");
        r.intensity = constant(g, l.intensity, l.loc, "the light intensity");
        r.radius = constant(g, l.radius, l.loc, "the light radius");
        cs.lights.push_back(r);
    }
    cs.ambient = constant3(g, scene.ambient, c.loc, "the ambient color");
    cs.background = constant3(g, scene.background, c.loc, "the background color");
    cs.render = scene.render;
    SceneBounds sb = scene_bounds(scene);
    if (const NodeId solid = solid_without_floors(g, scene, sb); solid != kNoNode) {
        cs.solid = codegen(g, {solid}, {"d"});
        check_constants(cs.solid);
    }
    cs.bounds = sb.bounds;
    cs.solid_bounds = sb.solid_bounds;
    cs.half_spaces = std::move(sb.half_spaces);
    cs.is_2d = scene.is_2d;
    cs.raw_field = scene.raw_field;
    cs.time = scene.time;
    // (not where the bounds may move with time: an animation's camera would follow them)
    if (!c.loc.known() && !scene.is_2d && !scene.raw_field && !scene.reads_time) frame_default_camera(cs);
    return cs;
}

}  // namespace sdfc
