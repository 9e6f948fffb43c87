// The built-in names: parameter tables, argument binding with diagnostics that name the
// parameter, and what each builtin builds (a Shape, a modifier, a setting, a math node).
#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "compiler/scene/lower.hpp"
#include "lang/interp.hpp"

namespace sdfc {
namespace {

ParamSpec req(const char* n, PT t) { return ParamSpec{n, t, false, {}}; }
ParamSpec opt(const char* n, PT t, float a, float b = 0, float c = 0) { return ParamSpec{n, t, true, {a, b, c}}; }
ParamSpec opt3(const char* n, PT t, float v) { return ParamSpec{n, t, true, {v, v, v}}; }

std::vector<BuiltinInfo> make_table() {
    using P = PT;
    std::vector<BuiltinInfo> t;
    auto add = [&](Builtin id, const char* name, BuiltinKind k, std::vector<ParamSpec> ps) {
        t.push_back(BuiltinInfo{id, name, k, std::move(ps)});
    };
    using B = Builtin;
    using K = BuiltinKind;
    // Primitives
    add(B::Sphere, "sphere", K::Shape, {req("r", P::Num)});
    add(B::Box, "box", K::Shape, {req("size", P::NumOrVec3)});
    add(B::RoundBox, "round_box", K::Shape, {req("size", P::NumOrVec3), req("r", P::Num)});
    add(B::BoxFrame, "box_frame", K::Shape, {req("size", P::NumOrVec3), req("e", P::Num)});
    add(B::Torus, "torus", K::Shape, {req("major", P::Num), req("minor", P::Num)});
    add(B::CappedTorus, "capped_torus", K::Shape, {req("angle", P::Num), req("major", P::Num), req("minor", P::Num)});
    add(B::Link, "link", K::Shape, {req("length", P::Num), req("major", P::Num), req("minor", P::Num)});
    add(B::Cylinder, "cylinder", K::Shape, {req("h", P::Num), req("r", P::Num)});
    add(B::RoundCylinder, "round_cylinder", K::Shape, {req("h", P::Num), req("r", P::Num), req("edge", P::Num)});
    add(B::Capsule, "capsule", K::Shape, {req("a", P::Vec3), req("b", P::Vec3), req("r", P::Num)});
    add(B::Cone, "cone", K::Shape, {req("h", P::Num), req("r1", P::Num), opt("r2", P::Num, 0)});
    add(B::Plane, "plane", K::Shape, {opt("normal", P::Vec3, 0, 1, 0), opt("offset", P::Num, 0)});
    add(B::Ellipsoid, "ellipsoid", K::Shape, {req("radii", P::NumOrVec3)});
    add(B::Octahedron, "octahedron", K::Shape, {req("s", P::Num)});
    add(B::Pyramid, "pyramid", K::Shape, {req("h", P::Num)});
    add(B::HexPrism, "hex_prism", K::Shape, {req("h", P::Num), req("r", P::Num)});
    add(B::TriPrism, "tri_prism", K::Shape, {req("h", P::Num), req("r", P::Num)});
    add(B::Gyroid, "gyroid", K::Shape, {req("period", P::Num), req("thickness", P::Num)});
    add(B::SchwarzP, "schwarz_p", K::Shape, {req("period", P::Num), req("thickness", P::Num)});
    add(B::EmptyShape, "empty", K::Shape, {});
    // Operations
    for (auto [id, name] : {std::pair{B::Union, "union"}, {B::Intersection, "intersection"}, {B::Difference, "difference"}, {B::Xor, "xor"}})
        add(id, name, K::Modifier, {});
    for (auto [id, name] : {std::pair{B::SmoothUnion, "smooth_union"}, {B::SmoothIntersection, "smooth_intersection"},
                            {B::SmoothDifference, "smooth_difference"}})
        add(id, name, K::Modifier, {req("k", P::Num)});
    for (auto [id, name] : {std::pair{B::ChamferUnion, "chamfer_union"}, {B::ChamferIntersection, "chamfer_intersection"},
                            {B::ChamferDifference, "chamfer_difference"}})
        add(id, name, K::Modifier, {req("r", P::Num)});
    for (auto [id, name] : {std::pair{B::StairsUnion, "stairs_union"}, {B::StairsIntersection, "stairs_intersection"},
                            {B::StairsDifference, "stairs_difference"}})
        add(id, name, K::Modifier, {req("r", P::Num), req("n", P::Num)});
    add(B::Translate, "translate", K::Modifier, {req("v", P::Vec3)});
    add(B::Rotate, "rotate", K::Modifier,
        {opt("angle", P::Any, 0), opt("axis", P::Vec3, 0, 0, 1), opt("x", P::Num, 0), opt("y", P::Num, 0), opt("z", P::Num, 0)});
    add(B::Scale, "scale", K::Modifier, {req("s", P::NumOrVec3)});
    add(B::Mirror, "mirror", K::Modifier, {req("normal", P::Vec3)});
    add(B::Repeat, "repeat", K::Modifier, {req("period", P::NumOrVec3), opt3("count", P::NumOrVec3, -1)});
    add(B::PolarRepeat, "polar_repeat", K::Modifier, {req("n", P::Num)});
    add(B::Symmetry, "symmetry", K::Modifier, {opt("x", P::Bool, 0), opt("y", P::Bool, 0), opt("z", P::Bool, 0)});
    add(B::Elongate, "elongate", K::Modifier, {req("v", P::NumOrVec3)});
    add(B::Twist, "twist", K::Modifier, {req("rate", P::Num)});
    add(B::Bend, "bend", K::Modifier, {req("rate", P::Num)});
    add(B::Round, "round", K::Modifier, {req("r", P::Num)});
    add(B::Onion, "onion", K::Modifier, {req("thickness", P::Num)});
    add(B::Displace, "displace", K::Modifier, {req("amount", P::Num), opt("frequency", P::Num, 1)});
    add(B::MaterialFn, "material", K::MaterialCtor,
        {opt("m", P::Material, 0), opt("color", P::Vec3, 0.8f, 0.8f, 0.8f), opt("specular", P::Num, 0.5f),
         opt("shininess", P::Num, 32), opt("reflect", P::Num, 0), opt("transparency", P::Num, 0), opt("ior", P::Num, 1.5f),
         opt("emission", P::Vec3, 0, 0, 0)});
    add(B::Color, "color", K::MaterialCtor, {req("color", P::Vec)});  // named like material's and ambient's
    // Settings
    add(B::Camera, "camera", K::Setting,
        {opt("position", P::Vec3, 0, 0, 5), opt("target", P::Vec3, 0, 0, 0), opt("up", P::Vec3, 0, 1, 0), opt("fov", P::Num, 45),
         opt("projection", P::String, 0), opt("ortho_height", P::Num, 2)});
    add(B::Light, "light", K::Setting,
        {opt("position", P::Vec3, 0, 0, 0), opt("color", P::Vec3, 1, 1, 1), opt("intensity", P::Num, 1), opt("radius", P::Num, 0),
         opt("direction", P::Vec3, 0, -1, 0)});
    add(B::Ambient, "ambient", K::Setting, {req("color", P::NumOrVec3)});
    add(B::Background, "background", K::Setting, {req("color", P::NumOrVec3)});
    add(B::Render, "render", K::Setting,
        {opt("width", P::Num, 640), opt("height", P::Num, 480), opt("samples", P::Num, 1), opt("max_steps", P::Num, 256),
         opt("max_distance", P::Num, 100), opt("epsilon", P::Num, 1e-4f), opt("shadows", P::Bool, 1), opt("ao", P::Bool, 1),
         opt("max_bounces", P::Num, 3), opt("aa", P::String, 0)});
    // Math: parameters are checked by call_math.
    const char* math[] = {"sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sqrt", "pow", "exp", "log", "abs",
                          "sign", "floor", "ceil", "fract", "mod", "min", "max", "clamp", "mix", "step", "smoothstep",
                          "length", "distance", "dot", "cross", "normalize", "radians", "degrees", "noise"};
    for (const char* m : math) {
        Builtin id{};
#define SDFC_BUILTIN(i, n, k) if (std::strcmp(n, m) == 0) id = Builtin::i;
#include "lang/builtins.def"
#undef SDFC_BUILTIN
        add(id, m, K::Math, {});
    }
    std::sort(t.begin(), t.end(), [](const BuiltinInfo& a, const BuiltinInfo& b) { return a.id < b.id; });
    return t;
}

const std::vector<BuiltinInfo>& table() {
    static const std::vector<BuiltinInfo> t = make_table();
    return t;
}

}  // namespace

const BuiltinInfo& builtin_info(Builtin id) { return table()[static_cast<size_t>(id)]; }

const BuiltinInfo* find_builtin(std::string_view name) {
    for (const auto& b : table())
        if (name == b.name) return &b;
    return nullptr;
}

const std::vector<std::string>& builtin_names() {
    static const std::vector<std::string> names = [] {
        std::vector<std::string> v;
        for (const auto& b : table()) v.push_back(b.name);
        return v;
    }();
    return names;
}

namespace {

// Binds call arguments to a builtin's parameters, checking count, names and types.
struct Binder {
    Interp& in;
    const BuiltinInfo& info;
    BoundArgs out;

    void bind(const std::vector<ast::Arg>& args, Env* env, Loc loc) {
        out.call_loc = loc;
        out.values.resize(info.params.size());
        out.locs.resize(info.params.size(), loc);
        size_t pos = 0;
        bool named = false;
        for (const auto& a : args) {
            size_t idx;
            if (a.name.empty()) {
                if (named) in.fail(a.loc, "a positional argument cannot follow a named one");
                if (pos >= info.params.size()) {
                    if (info.params.empty()) in.fail(a.loc, fmt::format("{} takes no arguments", info.name));
                    std::string names;
                    for (const auto& p : info.params) names += (names.empty() ? "" : ", ") + std::string(p.name);
                    in.fail(a.loc, fmt::format("{} takes at most {} argument{} ({}), but more were given", info.name,
                                               info.params.size(), info.params.size() == 1 ? "" : "s", names));
                }
                idx = pos++;
            } else {
                named = true;
                auto it = std::find_if(info.params.begin(), info.params.end(), [&](const ParamSpec& p) { return a.name == p.name; });
                if (it == info.params.end()) {
                    std::vector<std::string> names;
                    for (const auto& p : info.params) names.push_back(p.name);
                    std::string near = nearest_name(a.name, names);
                    in.fail(a.loc, near.empty() ? fmt::format("{} has no parameter '{}'", info.name, a.name)
                                                : fmt::format("{} has no parameter '{}' (did you mean `{}`?)", info.name, a.name, near));
                }
                idx = size_t(it - info.params.begin());
                if (out.values[idx]) in.fail(a.loc, fmt::format("argument '{}' of {} is given twice", a.name, info.name));
            }
            Value v = in.eval(*a.value, env);
            check_type(info.params[idx], v, a.value->loc);
            out.values[idx] = std::make_unique<Value>(std::move(v));
            out.locs[idx] = a.value->loc;
        }
    }

    void check_type(const ParamSpec& p, const Value& v, Loc loc) {
        auto bad = [&](const char* want) {
            in.fail(loc, fmt::format("argument '{}' of {} must be {}, not {}", p.name, info.name, want, in.describe(v)));
        };
        switch (p.type) {
            case PT::Num: if (v.t != VT::Number) bad("a number"); break;
            case PT::Vec3: if (!(v.t == VT::Vector && v.n == 3)) bad("a 3-component vector"); break;
            case PT::NumOrVec3: if (!(v.t == VT::Number || (v.t == VT::Vector && v.n == 3))) bad("a number or a 3-component vector"); break;
            case PT::Vec: if (v.t != VT::Vector) bad("a vector"); break;
            case PT::Bool: if (v.t != VT::Bool && v.t != VT::Number) bad("true or false"); break;
            case PT::String: if (v.t != VT::String) bad("a string"); break;
            case PT::Material: if (v.t != VT::Material) bad("a material"); break;
            case PT::Any: break;
        }
    }

    bool has(size_t i) const { return out.values[i] != nullptr; }
    const Value& val(size_t i) const { return *out.values[i]; }
    Loc loc(size_t i) const { return out.locs[i]; }

    void require(size_t i) {
        if (!has(i) && !info.params[i].has_default) in.fail(out.call_loc, fmt::format("missing argument '{}' of {}", info.params[i].name, info.name));
    }
    NodeId num(size_t i) {
        if (has(i)) return in.num(val(i), loc(i), info.params[i].name);
        require(i);
        return in.g->constant(info.params[i].def[0]);
    }
    Vec3N vec3(size_t i) {
        if (has(i)) return in.vec3(val(i), loc(i), info.params[i].name, info.params[i].type == PT::NumOrVec3);
        require(i);
        const auto& d = info.params[i].def;
        return {in.g->constant(d[0]), in.g->constant(d[1]), in.g->constant(d[2])};
    }
    NodeId boolean(size_t i) {
        if (has(i)) return in.truth(val(i), loc(i));
        require(i);
        return in.g->constant(info.params[i].def[0]);
    }
    // A size: a constant must be finite and not negative (zero allowed).
    NodeId size(size_t i, bool positive = false) {
        NodeId n = num(i);
        check_size(n, i, positive);
        return n;
    }
    void check_size(NodeId n, size_t i, bool positive) {
        if (!in.g->is_const(n)) return;
        float v = in.g->const_value(n);
        if (std::isnan(v)) in.fail(loc(i), fmt::format("argument '{}' of {} is not a number (NaN)", info.params[i].name, info.name));
        if (!std::isfinite(v)) in.fail(loc(i), fmt::format("argument '{}' of {} must be finite", info.params[i].name, info.name));
        if (v < 0 || (positive && v == 0))
            in.fail(loc(i), fmt::format("argument '{}' of {} must be {}, not {}", info.params[i].name, info.name,
                                        positive ? "positive" : "zero or positive", v));
    }
    Vec3N size3(size_t i, bool positive = false) {
        Vec3N v = vec3(i);
        for (NodeId n : v) check_size(n, i, positive);
        return v;
    }
    // A constant from lo to hi (a value known only per time is clamped where it is used).
    void range(NodeId n, size_t i, float lo, float hi) {
        finite(n, i);
        if (in.g->is_const(n) && !(in.g->const_value(n) >= lo && in.g->const_value(n) <= hi))
            in.fail(loc(i), fmt::format("argument '{}' of {} must be from {} to {}, not {}", info.params[i].name, info.name, lo,
                                        hi, in.g->const_value(n)));
    }
    void finite(NodeId n, size_t i) {
        if (in.g->is_const(n) && !std::isfinite(in.g->const_value(n)))
            in.fail(loc(i), fmt::format("argument '{}' of {} must be a finite number", info.params[i].name, info.name));
    }
};

void push3(std::vector<NodeId>& v, const Vec3N& a) { v.insert(v.end(), a.begin(), a.end()); }

MaterialN material_from(Interp& in, Binder& b, const MaterialN* base) {
    Graph& g = *in.g;
    MaterialN m = base ? *base : default_material(g);
    auto set3 = [&](size_t i, int ch) {
        if (!b.has(i)) return;
        Vec3N v = b.vec3(i);
        for (int k = 0; k < 3; ++k) m[ch + k] = v[k];
    };
    auto set1 = [&](size_t i, int ch) {
        if (b.has(i)) m[ch] = b.size(i);
    };
    set3(1, kMatR);
    set1(2, kMatSpecular);
    set1(3, kMatShininess);
    set1(4, kMatReflect);
    set1(5, kMatTransparency);
    set1(6, kMatIor);
    set3(7, kMatEmitR);
    return m;
}

}  // namespace

Value Interp::call_builtin(const BuiltinInfo& info, const std::vector<ast::Arg>& args, Env* env, Loc loc) {
    if (info.kind == BuiltinKind::Math) {
        std::vector<Value> vals;
        std::vector<Loc> locs;
        for (const auto& a : args) {
            if (!a.name.empty()) fail(a.loc, fmt::format("{} takes positional arguments only", info.name));
            vals.push_back(eval(*a.value, env));
            locs.push_back(a.value->loc);
        }
        g->set_loc(loc);
        Value r = call_math(info, vals, locs, loc);
        // Most results were checked component by component; this also covers the
        // reductions (length, dot, distance, cross...), which can overflow too.
        for (int i = 0; i < r.n; ++i) checked(r.c[i], loc);
        return r;
    }
    Binder b{*this, info, {}};
    b.bind(args, env, loc);
    g->set_loc(loc);
    Graph& gr = *g;
    using B = Builtin;
    if (info.kind == BuiltinKind::Shape) {
        Shape s{ShapeKind::Empty, loc};
        auto& p = s.params;
        switch (info.id) {
            case B::Sphere: s.kind = ShapeKind::Sphere; p = {b.size(0)}; break;
            case B::Box: s.kind = ShapeKind::Box; push3(p, b.size3(0)); break;
            case B::RoundBox: s.kind = ShapeKind::RoundBox; push3(p, b.size3(0)); p.push_back(b.size(1)); break;
            case B::BoxFrame: s.kind = ShapeKind::BoxFrame; push3(p, b.size3(0)); p.push_back(b.size(1)); break;
            case B::Torus: s.kind = ShapeKind::Torus; p = {b.size(0), b.size(1)}; break;
            case B::CappedTorus: s.kind = ShapeKind::CappedTorus; p = {b.num(0), b.size(1), b.size(2)}; b.range(p[0], 0, 0, 360); break;
            case B::Link: s.kind = ShapeKind::Link; p = {b.size(0), b.size(1), b.size(2)}; break;
            case B::Cylinder: s.kind = ShapeKind::Cylinder; p = {b.size(0), b.size(1)}; break;
            case B::RoundCylinder: s.kind = ShapeKind::RoundCylinder; p = {b.size(0), b.size(1), b.size(2)}; break;
            case B::Capsule: {
                s.kind = ShapeKind::Capsule;
                Vec3N a = b.vec3(0), c = b.vec3(1);
                for (NodeId n : a) b.finite(n, 0);
                for (NodeId n : c) b.finite(n, 1);
                push3(p, a);
                push3(p, c);
                p.push_back(b.size(2));
                break;
            }
            case B::Cone: {
                s.kind = ShapeKind::Cone;
                p = {b.size(0), b.size(1), b.size(2)};
                bool all_zero = true;  // 0/0 in the distance: a NaN naming no parameter
                for (NodeId n : p) all_zero &= gr.is_const(n) && gr.const_value(n) == 0.0f;
                if (all_zero) fail(b.loc(0), "a cone needs a height h or a radius r1, r2 above zero (all three are 0)");
                break;
            }
            case B::Plane: {
                s.kind = ShapeKind::Plane;
                Vec3N n = b.vec3(0);
                bool zero = true;
                for (NodeId c : n) {
                    b.finite(c, 0);
                    zero &= gr.is_const(c) && gr.const_value(c) == 0.0f;
                }
                if (zero) fail(b.loc(0), "the plane's normal must not be zero");
                push3(p, n);
                p.push_back(b.num(1));
                b.finite(p[3], 1);
                break;
            }
            case B::Ellipsoid: s.kind = ShapeKind::Ellipsoid; push3(p, b.size3(0, true)); break;
            case B::Octahedron: s.kind = ShapeKind::Octahedron; p = {b.size(0)}; break;
            case B::Pyramid: s.kind = ShapeKind::Pyramid; p = {b.size(0)}; break;
            case B::HexPrism: s.kind = ShapeKind::HexPrism; p = {b.size(0), b.size(1)}; break;
            case B::TriPrism: s.kind = ShapeKind::TriPrism; p = {b.size(0), b.size(1)}; break;
            case B::Gyroid: s.kind = ShapeKind::Gyroid; p = {b.size(0, true), b.size(1)}; break;
            case B::SchwarzP: s.kind = ShapeKind::SchwarzP; p = {b.size(0, true), b.size(1)}; break;
            case B::EmptyShape: s.kind = ShapeKind::Empty; break;
            default: fail(loc, "internal: unknown shape");
        }
        return Value::of_shape(make_shape(std::move(s)));
    }
    if (info.kind == BuiltinKind::Modifier) {
        auto m = std::make_shared<ModifierVal>();
        m->id = info.id;
        m->name = info.name;
        m->loc = loc;
        // Validate eagerly so errors point at the call even before a target is seen.
        switch (info.id) {
            case B::SmoothUnion: case B::SmoothIntersection: case B::SmoothDifference:
            case B::ChamferUnion: case B::ChamferIntersection: case B::ChamferDifference:
            case B::Round: case B::Onion: case B::Twist: case B::Bend:
                b.num(0);
                b.finite(b.num(0), 0);
                if (info.id != B::Twist && info.id != B::Bend && info.id != B::Round) b.size(0);
                break;
            case B::StairsUnion: case B::StairsIntersection: case B::StairsDifference:
                b.size(0);
                b.size(1, true);
                break;
            case B::Scale: b.size3(0, true); break;
            case B::PolarRepeat: {
                NodeId n = b.size(0, true);
                if (gr.is_const(n) && gr.const_value(n) != std::floor(gr.const_value(n)))
                    fail(b.loc(0), "argument 'n' of polar_repeat must be a whole number");
                break;
            }
            case B::Mirror: {
                Vec3N n = b.vec3(0);
                bool zero = true;
                for (NodeId c : n) zero &= gr.is_const(c) && gr.const_value(c) == 0.0f;
                if (zero) fail(b.loc(0), "the mirror's normal must not be zero");
                break;
            }
            case B::Repeat: {
                b.size3(0);
                if (b.has(1)) b.size3(1);
                break;
            }
            case B::Displace: b.finite(b.num(0), 0); b.size(1); break;
            case B::Translate: for (NodeId n : b.vec3(0)) b.finite(n, 0); break;
            case B::Elongate: b.size3(0); break;
            default: break;
        }
        m->args = std::make_shared<BoundArgs>(std::move(b.out));
        Value v;
        v.t = VT::Modifier;
        v.mod = m;
        return v;
    }
    if (info.kind == BuiltinKind::MaterialCtor) {
        MaterialN mat;
        if (info.id == B::Color) {
            mat = default_material(gr);
            if (b.has(0)) {
                const Value& c = b.val(0);
                if (c.n < 3) fail(b.loc(0), "color takes [r, g, b]");
                for (int k = 0; k < 3; ++k) mat[kMatR + k] = c.c[k];
            } else {
                // `color` with no argument only makes sense applied; use the default.
            }
        } else {
            const MaterialN* base = b.has(0) ? b.val(0).mat.get() : nullptr;
            mat = material_from(*this, b, base);
        }
        Value v;
        v.t = VT::Material;
        v.mat = std::make_shared<const MaterialN>(mat);
        return v;
    }
    // Settings
    auto once = [&](Loc& at, const char* what) {
        if (at.known()) fail(loc, fmt::format("a second {} statement (the first is at line {})", what, at.line));
        at = loc;
    };
    switch (info.id) {
        case B::Camera: {
            once(camera_at, "camera");
            CameraSettings& c = scene.camera;
            c.loc = loc;
            c.position = b.vec3(0);
            c.target = b.vec3(1);
            c.up = b.vec3(2);
            c.fov = b.num(3);
            if (gr.is_const(c.fov) && !(gr.const_value(c.fov) > 0 && gr.const_value(c.fov) < 180))
                fail(b.loc(3), "the camera's fov must be between 0 and 180 degrees");
            if (b.has(4)) {
                const std::string& pr = *b.val(4).str;
                if (pr == "orthographic") c.orthographic = true;
                else if (pr != "perspective")
                    fail(b.loc(4), fmt::format("projection must be \"perspective\" or \"orthographic\", not \"{}\"", pr));
            }
            c.ortho_height = b.size(5, true);
            break;
        }
        case B::Light: {
            if (b.has(0) && b.has(4)) fail(loc, "a light has either a position (point light) or a direction (directional light), not both");
            LightSettings l;
            l.loc = loc;
            l.directional = b.has(4);
            if (!b.has(0) && !b.has(4)) fail(loc, "a light needs a position (point light) or a direction (directional light)");
            l.position = b.vec3(0);
            l.direction = b.vec3(4);
            if (l.directional) {
                bool zero = true;
                for (NodeId c : l.direction) zero &= gr.is_const(c) && gr.const_value(c) == 0.0f;
                if (zero) fail(b.loc(4), "the light's direction must not be zero");
            }
            l.color = b.vec3(1);
            l.intensity = b.size(2);
            l.radius = b.size(3);
            scene.lights.push_back(l);
            break;
        }
        case B::Ambient:
            once(ambient_at, "ambient");
            scene.ambient = b.vec3(0);
            break;
        case B::Background:
            once(background_at, "background");
            scene.background = b.vec3(0);
            break;
        case B::Render: {
            once(render_at, "render");
            RenderSettings& r = scene.render;
            r.loc = loc;
            auto whole = [&](size_t i, int lo, int hi) {
                float v = const_num(b.has(i) ? b.val(i) : Value::number(gr.constant(info.params[i].def[0])), b.loc(i), info.params[i].name);
                if (!(v >= float(lo) && v <= float(hi)) || v != std::floor(v))
                    fail(b.loc(i), fmt::format("render {} must be a whole number from {} to {}, not {}", info.params[i].name, lo, hi,
                                               // whole numbers in full: 2147483648, not float's 2147483600
                                               std::fabs(v) < 1e15f && v == std::floor(v) ? fmt::format("{}", (long long)v) : fmt::format("{}", v)));
                return int(v);
            };
            r.width = whole(0, 1, 16384);
            r.height = whole(1, 1, 16384);
            r.samples = whole(2, 1, 1024);
            r.max_steps = whole(3, 1, 100000);
            r.max_distance = const_num(Value::number(b.size(4, true)), b.loc(4), "max_distance");
            r.epsilon = const_num(Value::number(b.size(5, true)), b.loc(5), "epsilon");
            r.shadows = const_num(Value::number(b.boolean(6)), b.loc(6), "shadows") != 0;
            r.ao = const_num(Value::number(b.boolean(7)), b.loc(7), "ao") != 0;
            r.max_bounces = whole(8, 0, 64);
            if (b.has(9)) {
                const std::string& aa = *b.val(9).str;
                if (aa != "grid" && aa != "cone") fail(b.loc(9), fmt::format("aa must be \"grid\" or \"cone\", not \"{}\"", aa));
                r.aa = aa;
            }
            break;
        }
        default:
            fail(loc, "internal: unknown setting");
    }
    return Value{};
}

ShapePtr Interp::apply_modifier(const ModifierVal& m, ShapePtr target, Loc loc) {
    using B = Builtin;
    Graph& gr = *g;
    g->set_loc(m.loc);
    static const BoundArgs kNoArgs;  // material()/color() modifiers carry none
    const BoundArgs& a = m.args ? *m.args : kNoArgs;
    auto arg = [&](size_t i) -> const Value* { return a.get(i); };
    auto n0 = [&](size_t i, float def) { return arg(i) ? num(*arg(i), a.locs[i], "argument") : gr.constant(def); };
    auto v3 = [&](size_t i, float def) {
        return arg(i) ? vec3(*arg(i), a.locs[i], "argument", true) : Vec3N{gr.constant(def), gr.constant(def), gr.constant(def)};
    };
    Shape s{ShapeKind::Union, m.loc};
    auto csg = [&](ShapeKind k) {
        // A CSG operation takes the statements of its block as operands; a single shape
        // that is itself a union of a block's statements is opened up. A `for` statement is
        // one operand, the union of its iterations; the union-like operations take its
        // iterations as operands instead (the same union, and smooth ones blend them).
        s.kind = k;
        if (target->kind == ShapeKind::Union && !target->iterations && !target->children.empty()) s.children = target->children;
        else s.children = {target};
        const bool union_like = k == ShapeKind::Union || k == ShapeKind::SmoothUnion || k == ShapeKind::ChamferUnion ||
                                k == ShapeKind::StairsUnion;
        if (union_like && std::any_of(s.children.begin(), s.children.end(), [](const ShapePtr& c) { return c->iterations; })) {
            std::vector<ShapePtr> flat;
            for (const ShapePtr& c : s.children) {
                if (c->iterations) flat.insert(flat.end(), c->children.begin(), c->children.end());
                else flat.push_back(c);
            }
            s.children = std::move(flat);
        }
    };
    switch (m.id) {
        case B::Union: csg(ShapeKind::Union); break;
        case B::Intersection: csg(ShapeKind::Intersection); break;
        case B::Difference: csg(ShapeKind::Difference); break;
        case B::Xor: csg(ShapeKind::Xor); break;
        case B::SmoothUnion: csg(ShapeKind::SmoothUnion); s.params = {n0(0, 0)}; break;
        case B::SmoothIntersection: csg(ShapeKind::SmoothIntersection); s.params = {n0(0, 0)}; break;
        case B::SmoothDifference: csg(ShapeKind::SmoothDifference); s.params = {n0(0, 0)}; break;
        case B::ChamferUnion: csg(ShapeKind::ChamferUnion); s.params = {n0(0, 0)}; break;
        case B::ChamferIntersection: csg(ShapeKind::ChamferIntersection); s.params = {n0(0, 0)}; break;
        case B::ChamferDifference: csg(ShapeKind::ChamferDifference); s.params = {n0(0, 0)}; break;
        case B::StairsUnion: csg(ShapeKind::StairsUnion); s.params = {n0(0, 0), n0(1, 1)}; break;
        case B::StairsIntersection: csg(ShapeKind::StairsIntersection); s.params = {n0(0, 0), n0(1, 1)}; break;
        case B::StairsDifference: csg(ShapeKind::StairsDifference); s.params = {n0(0, 0), n0(1, 1)}; break;
        case B::Translate: s.kind = ShapeKind::Translate; push3(s.params, v3(0, 0)); s.children = {target}; break;
        case B::Rotate: {
            s.kind = ShapeKind::Rotate;
            std::array<NodeId, 9> r;
            bool xyz = arg(2) || arg(3) || arg(4);
            const Value* ang = arg(0);
            if (xyz && (ang || arg(1))) fail(m.loc, "rotate takes either x=, y=, z= or an angle and an axis, not both");
            if (xyz) {
                r = rotation_xyz(gr, n0(2, 0), n0(3, 0), n0(4, 0));
            } else if (ang && ang->t == VT::Vector) {
                if (ang->n != 3) fail(a.locs[0], "rotate([x, y, z]) takes a 3-component vector of angles");
                if (arg(1)) fail(a.locs[1], "rotate([x, y, z]) takes no axis");
                r = rotation_xyz(gr, ang->c[0], ang->c[1], ang->c[2]);
            } else if (ang) {
                NodeId an = num(*ang, a.locs[0], "argument 'angle' of rotate");
                Vec3N axis = arg(1) ? vec3(*arg(1), a.locs[1], "argument 'axis' of rotate", false)
                                    : Vec3N{gr.constant(0), gr.constant(0), gr.constant(1)};
                bool zero = true;
                for (NodeId c : axis) zero &= gr.is_const(c) && gr.const_value(c) == 0.0f;
                if (zero) fail(a.locs[1], "the rotation axis must not be zero");
                r = rotation_axis_angle(gr, an, axis);
            } else {
                r = rotation_xyz(gr, gr.constant(0), gr.constant(0), gr.constant(0));
            }
            s.params.assign(r.begin(), r.end());
            s.children = {target};
            break;
        }
        case B::Scale: s.kind = ShapeKind::Scale; push3(s.params, v3(0, 1)); s.children = {target}; break;
        case B::Mirror: {
            s.kind = ShapeKind::Mirror;
            Vec3N n = v3(0, 0);
            NodeId len = gr.ternary(Op::Length3, n[0], n[1], n[2]);
            s.params = {gr.div(n[0], len), gr.div(n[1], len), gr.div(n[2], len)};
            s.children = {target};
            break;
        }
        case B::Repeat: {
            Vec3N per = v3(0, 0);
            push3(s.params, per);
            if (arg(1)) {
                s.kind = ShapeKind::RepeatFinite;
                Vec3N c = v3(1, 0);
                for (NodeId& n : c) n = gr.unary(Op::Floor, n);
                push3(s.params, c);
            } else {
                s.kind = ShapeKind::Repeat;
            }
            s.children = {target};
            break;
        }
        case B::PolarRepeat: s.kind = ShapeKind::PolarRepeat; s.params = {n0(0, 1)}; s.children = {target}; break;
        case B::Symmetry: {
            s.kind = ShapeKind::Symmetry;
            // LANGUAGE.md writes symmetry(x=true, y=, z=): x is folded unless y or z is named
            // (a bare `symmetry()` mirrors x; `symmetry(y = true)` only y).
            const bool x_default = !arg(1) && !arg(2);
            for (size_t i = 0; i < 3; ++i)
                s.params.push_back(arg(i) ? truth(*arg(i), a.locs[i]) : gr.constant(i == 0 && x_default ? 1.0f : 0.0f));
            s.children = {target};
            break;
        }
        case B::Elongate: s.kind = ShapeKind::Elongate; push3(s.params, v3(0, 0)); s.children = {target}; break;
        case B::Twist: s.kind = ShapeKind::Twist; s.params = {n0(0, 0)}; s.children = {target}; break;
        case B::Bend: s.kind = ShapeKind::Bend; s.params = {n0(0, 0)}; s.children = {target}; break;
        case B::Round: s.kind = ShapeKind::Round; s.params = {n0(0, 0)}; s.children = {target}; break;
        case B::Onion: s.kind = ShapeKind::Onion; s.params = {n0(0, 0)}; s.children = {target}; break;
        case B::Displace: s.kind = ShapeKind::Displace; s.params = {n0(0, 0), n0(1, 1)}; s.children = {target}; break;
        case B::MaterialFn:
        case B::Color:
            s.kind = ShapeKind::Material;
            s.material = m.material;
            s.children = {target};
            break;
        default:
            fail(loc, fmt::format("internal: {} is not an operation", m.name));
    }
    return make_shape(std::move(s));
}

Value Interp::call_math(const BuiltinInfo& info, std::vector<Value>& args, const std::vector<Loc>& locs, Loc loc) {
    Graph& gr = *g;
    using B = Builtin;
    auto arity = [&](size_t lo, size_t hi) {
        if (args.size() < lo || args.size() > hi) {
            if (lo == hi) fail(loc, fmt::format("{} takes {} argument{}, not {}", info.name, lo, lo == 1 ? "" : "s", args.size()));
            fail(loc, fmt::format("{} takes {} to {} arguments, not {}", info.name, lo, hi, args.size()));
        }
        for (size_t i = 0; i < args.size(); ++i)
            if (!args[i].numeric())
                fail(locs[i], fmt::format("argument {} of {} must be a number or a vector, not {}", i + 1, info.name, describe(args[i])));
    };
    auto un = [&](Op op) {
        arity(1, 1);
        return componentwise(args[0], loc, [&](NodeId x) { return gr.unary(op, x); });
    };
    auto bin = [&](Op op) {
        arity(2, 2);
        return componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) { return gr.binary(op, x, y); });
    };
    auto need_vec = [&](size_t i) {
        if (args[i].t != VT::Vector) fail(locs[i], fmt::format("argument {} of {} must be a vector, not {}", i + 1, info.name, describe(args[i])));
    };
    auto dot = [&](const Value& a, const Value& b) {
        if (a.n != b.n) fail(loc, fmt::format("{} needs vectors of one size, not {} and {} components", info.name, a.n, b.n));
        NodeId s = gr.mul(a.c[0], b.c[0]);
        for (int i = 1; i < a.n; ++i) s = gr.add(s, gr.mul(a.c[i], b.c[i]));
        return s;
    };
    auto length = [&](const Value& a) {
        if (a.t == VT::Number) return gr.abs(a.c[0]);
        if (a.n == 2) return gr.binary(Op::Length2, a.c[0], a.c[1]);
        if (a.n == 3) return gr.ternary(Op::Length3, a.c[0], a.c[1], a.c[2]);
        return gr.sqrt(dot(a, a));
    };
    switch (info.id) {
        case B::Sin: return un(Op::Sin);
        case B::Cos: return un(Op::Cos);
        case B::Tan: return un(Op::Tan);
        case B::Asin:
        case B::Acos: {
            // Like sqrt(-1): a constant out of the domain is an error; in a field (p varies)
            // the argument is clamped to [-1, 1] (docs/language.md).
            arity(1, 1);
            for (int i = 0; i < args[0].n; ++i)
                if (gr.is_const(args[0].c[i]) && !(std::fabs(gr.const_value(args[0].c[i])) <= 1.0f))
                    fail(locs[0], fmt::format("{} of a number outside [-1, 1] ({})", info.name, gr.const_value(args[0].c[i])));
            return un(info.id == B::Asin ? Op::Asin : Op::Acos);
        }
        case B::Atan:
            if (args.size() == 2) return bin(Op::Atan2);  // GLSL's atan(y, x)
            return un(Op::Atan);
        case B::Atan2: return bin(Op::Atan2);
        case B::Sqrt: {
            arity(1, 1);
            for (int i = 0; i < args[0].n; ++i)
                if (gr.is_const(args[0].c[i]) && gr.const_value(args[0].c[i]) < 0) fail(locs[0], "sqrt of a negative number");
            return un(Op::Sqrt);
        }
        case B::Pow: {
            arity(2, 2);
            return componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) {
                if (gr.is_const(x) && gr.is_const(y)) {
                    const float a = gr.const_value(x), e = gr.const_value(y);
                    if (a < 0 && std::floor(e) != e)
                        fail(locs[0], fmt::format("pow of a negative number ({}) to a fractional power ({}) is not a real number", a, e));
                    if (a == 0 && e < 0) fail(locs[0], fmt::format("pow of zero to a negative power ({})", e));
                }
                return gr.binary(Op::Pow, x, y);
            });
        }
        case B::Exp: return un(Op::Exp);
        case B::Log: {
            arity(1, 1);
            for (int i = 0; i < args[0].n; ++i)
                if (gr.is_const(args[0].c[i]) && gr.const_value(args[0].c[i]) <= 0) fail(locs[0], "log of a number that is not positive");
            return un(Op::Log);
        }
        case B::Abs: return un(Op::Abs);
        case B::Sign: return un(Op::Sign);
        case B::Floor: return un(Op::Floor);
        case B::Ceil: return un(Op::Ceil);
        case B::Fract: return un(Op::Fract);
        case B::Mod: {
            arity(2, 2);
            return componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) {
                if (gr.is_const(y) && gr.const_value(y) == 0.0f) fail(locs[1], "mod by zero");
                return gr.binary(Op::Mod, x, y);
            });
        }
        case B::Min:
        case B::Max: {
            if (args.size() == 1 && args[0].t == VT::Vector) {
                NodeId r = args[0].c[0];
                for (int i = 1; i < args[0].n; ++i) r = gr.binary(info.id == B::Min ? Op::Min : Op::Max, r, args[0].c[i]);
                return Value::number(r);
            }
            arity(2, 64);
            Value r = args[0];
            for (size_t i = 1; i < args.size(); ++i)
                r = componentwise2(r, args[i], loc, [&](NodeId x, NodeId y) { return gr.binary(info.id == B::Min ? Op::Min : Op::Max, x, y); });
            return r;
        }
        case B::Clamp: {
            arity(3, 3);
            Value lo = componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) { return gr.max(x, y); });
            return componentwise2(lo, args[2], loc, [&](NodeId x, NodeId y) { return gr.min(x, y); });
        }
        case B::Mix: {
            arity(3, 3);
            Value d = componentwise2(args[1], args[0], loc, [&](NodeId b, NodeId a) { return gr.sub(b, a); });
            Value t = componentwise2(d, args[2], loc, [&](NodeId x, NodeId k) { return gr.mul(x, k); });
            return componentwise2(args[0], t, loc, [&](NodeId a, NodeId x) { return gr.add(a, x); });
        }
        case B::Step: {
            arity(2, 2);
            // step(edge, x) = x < edge ? 0 : 1
            return componentwise2(args[0], args[1], loc, [&](NodeId edge, NodeId x) {
                return gr.sub(gr.constant(1), gr.binary(Op::Lt, x, edge));
            });
        }
        case B::Smoothstep: {
            arity(3, 3);
            Value w = componentwise2(args[1], args[0], loc, [&](NodeId b, NodeId a) { return gr.sub(b, a); });
            Value num_ = componentwise2(args[2], args[0], loc, [&](NodeId x, NodeId a) { return gr.sub(x, a); });
            Value t = componentwise2(num_, w, loc, [&](NodeId n, NodeId d) {
                if (gr.is_const(d) && gr.const_value(d) == 0.0f) fail(loc, "smoothstep with equal edges");
                return gr.clamp(gr.div(n, d), gr.constant(0), gr.constant(1));
            });
            return componentwise(t, loc, [&](NodeId x) {
                return gr.mul(gr.unary(Op::Square, x), gr.sub(gr.constant(3), gr.mul(gr.constant(2), x)));
            });
        }
        case B::Length: arity(1, 1); return Value::number(length(args[0]));
        case B::Distance: {
            arity(2, 2);
            Value d = componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) { return gr.sub(x, y); });
            return Value::number(length(d));
        }
        case B::Dot: arity(2, 2); need_vec(0); need_vec(1); return Value::number(dot(args[0], args[1]));
        case B::Cross: {
            arity(2, 2);
            need_vec(0);
            need_vec(1);
            const Value &a = args[0], &b = args[1];
            if (a.n != 3 || b.n != 3) fail(loc, "cross takes two 3-component vectors");
            NodeId c[3] = {gr.sub(gr.mul(a.c[1], b.c[2]), gr.mul(a.c[2], b.c[1])),
                           gr.sub(gr.mul(a.c[2], b.c[0]), gr.mul(a.c[0], b.c[2])),
                           gr.sub(gr.mul(a.c[0], b.c[1]), gr.mul(a.c[1], b.c[0]))};
            return Value::vector(c, 3);
        }
        case B::Normalize: {
            arity(1, 1);
            bool all_const = true, all_zero = true;
            for (int i = 0; i < args[0].n; ++i) {
                all_const &= gr.is_const(args[0].c[i]);
                all_zero &= gr.is_const(args[0].c[i]) && gr.const_value(args[0].c[i]) == 0.0f;
            }
            if (all_zero) fail(locs[0], "normalize of a zero vector");
            NodeId len = length(args[0]);
            const bool degenerate = gr.is_const(len) && !(gr.const_value(len) > 0.0f && std::isfinite(gr.const_value(len)));
            if (all_const && degenerate) {
                // In double: the float length of [1e-30, 0, 0] underflows to 0.
                double sq = 0;
                for (int i = 0; i < args[0].n; ++i) sq += double(gr.const_value(args[0].c[i])) * gr.const_value(args[0].c[i]);
                const double dl = std::sqrt(sq);
                NodeId c[4];
                for (int i = 0; i < args[0].n; ++i) c[i] = gr.constant(float(double(gr.const_value(args[0].c[i])) / dl));
                return args[0].t == VT::Number ? Value::number(c[0]) : Value::vector(c, args[0].n);
            }
            if (gr.is_const(len) && gr.const_value(len) == 0.0f) fail(locs[0], "normalize of a zero vector");
            return componentwise(args[0], loc, [&](NodeId x) { return gr.div(x, len); });
        }
        case B::Radians: arity(1, 1); return componentwise(args[0], loc, [&](NodeId x) { return gr.mulc(x, 3.14159265358979f / 180.0f); });
        case B::Degrees: arity(1, 1); return componentwise(args[0], loc, [&](NodeId x) { return gr.mulc(x, 180.0f / 3.14159265358979f); });
        case B::Noise: {
            arity(1, 1);
            Vec3N p = vec3(args[0], locs[0], "the argument of noise", false);
            return Value::number(gr.ternary(Op::Noise3, p[0], p[1], p[2]));
        }
        default: break;
    }
    fail(loc, fmt::format("internal: {} is not a math function", info.name));
}

}  // namespace sdfc
