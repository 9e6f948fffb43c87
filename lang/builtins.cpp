// The built-in names: parameter tables, argument binding with diagnostics that name the
// parameter, and what each builtin builds (a Shape, a modifier, a setting, a math node).
#include <algorithm>
#include <cmath>
#include <memory>
#include <string_view>
#include <unordered_map>

#include <fmt/format.h>

#include "compiler/scene/lower.hpp"
#include "lang/habits.hpp"
#include "lang/interp.hpp"

namespace sdfc {
namespace {

ParamSpec req(const char* n, PT t) { return ParamSpec{n, t, false, {}}; }
ParamSpec opt(const char* n, PT t, float a, float b = 0, float c = 0) { return ParamSpec{n, t, true, {a, b, c}}; }

std::vector<BuiltinInfo> make_table() {
    using P = PT;
    std::vector<BuiltinInfo> t;
    auto add = [&](Builtin id, const char* name, BuiltinKind k, std::vector<ParamSpec> ps) {
        t.push_back(BuiltinInfo{id, name, k, std::move(ps)});
    };
    using B = Builtin;
    using K = BuiltinKind;
    {
        // The shapes, from compiler/scene/shapes.def.
        using namespace param_check;
        auto shape = [&](Builtin id, const char* name, ShapeKind k, ShapeBuild build, std::vector<ParamSpec> ps) {
            add(id, name, shape_family(k) == ShapeFamily::Primitive ? K::Shape : K::Modifier, std::move(ps));
            t.back().shape = k;
            t.back().build = build;
        };
#define SDFC_P(name, type, checks, ...) ParamSpec{#name, P::type, false __VA_OPT__(|| true), {__VA_ARGS__}, checks, true},
#define SDFC_ARG(name, type, checks, ...) ParamSpec{#name, P::type, false __VA_OPT__(|| true), {__VA_ARGS__}, checks, false},
#define SDFC_SLOT(name, type)
#define SDFC_SHAPE(kind, name, family, build, params) shape(B::kind, name, ShapeKind::kind, ShapeBuild::build, {params});
#define SDFC_INNER_SHAPE(...)
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
#undef SDFC_P
#undef SDFC_ARG
#undef SDFC_SLOT
    }
    // material(m, then the parameters of compiler/scene/materials.def)
    std::vector<ParamSpec> mat{opt("m", P::Material, 0)};
    for (const MatChannelInfo& c : kMatChannelInfo) {
        if (c.component == 0) {
            mat.push_back(opt(c.param, P::Num, c.def));
        } else {
            mat.back().type = P::Vec3;
            mat.back().def[c.component] = c.def;
        }
    }
    add(B::MaterialFn, "material", K::MaterialCtor, std::move(mat));
    add(B::Color, "color", K::MaterialCtor, {req("color", P::Any), opt("alpha", P::Num, 1)});  // as material's; alpha: OpenSCAD's
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
         opt("max_bounces", P::Num, 3), opt("aa", P::String, 0), opt("exposure", P::Num, 1), opt("tonemap", P::String, 0)});
    // Math: parameters are checked by call_math.
#define SDFC_BUILTIN(i, n, k) \
    if (K::k == K::Math) add(B::i, n, K::Math, {});
#include "lang/builtins.def"
#undef SDFC_BUILTIN
    std::sort(t.begin(), t.end(), [](const BuiltinInfo& a, const BuiltinInfo& b) { return a.id < b.id; });
    return t;
}

const std::vector<BuiltinInfo>& table() {
    static const std::vector<BuiltinInfo> t = make_table();
    return t;
}

}  // namespace

const BuiltinInfo& builtin_info(Builtin id) { return table()[static_cast<size_t>(id)]; }

// A hash lookup: every call of a builtin in a script looks its name up (a 10,000-statement
// script makes 30,000 lookups, which a scan of the table spent 2 % of its check on).
const BuiltinInfo* find_builtin(std::string_view name) {
    static const std::unordered_map<std::string_view, const BuiltinInfo*> by_name = [] {
        std::unordered_map<std::string_view, const BuiltinInfo*> m;
        for (const auto& b : table()) m.emplace(b.name, &b);
        return m;
    }();
    const auto it = by_name.find(name);
    return it == by_name.end() ? nullptr : it->second;
}

const std::shared_ptr<const Callable>& builtin_callable(Builtin id) {
    static const std::vector<std::shared_ptr<const Callable>> fns = [] {
        std::vector<std::shared_ptr<const Callable>> v;
        for (const auto& b : table()) {
            auto fn = std::make_shared<Callable>();
            fn->name = b.name;
            fn->builtin = true;
            fn->id = b.id;
            v.push_back(std::move(fn));
        }
        return v;
    }();
    return fns[static_cast<size_t>(id)];
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
                    in.fail(a.loc, fmt::format("{} takes at most {} argument{} ({}), but more were given{}", info.name,
                                               info.params.size(), info.params.size() == 1 ? "" : "s", names,
                                               openscad_argument_hint(info.name, "")));
                }
                idx = pos++;
            } else {
                named = true;
                auto it = std::find_if(info.params.begin(), info.params.end(), [&](const ParamSpec& p) { return a.name == p.name; });
                if (it == info.params.end()) {
                    // OpenSCAD's arguments (d, center, r1, ...): the sdfc forms.
                    if (const std::string why = openscad_argument_hint(info.name, a.name); !why.empty())
                        in.fail(a.loc, fmt::format("{} has no parameter '{}': {}", info.name, a.name, why));
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
            // A colour parameter takes a name too: material(color = "tomato"), light(color = "white").
            const std::string_view pname = info.params[idx].name;
            if (v.t == VT::String && (pname == "color" || pname == "emission") && info.params[idx].type != PT::Any)
                v = in.colour_name(*v.str, a.value->loc);
            // OpenSCAD's [x, y] for a move, a mirror or a scale (2D profiles): z is 0, or 1 to scale.
            if (const std::string_view fn = info.name; idx == 0 && v.t == VT::Vector && v.n == 2 && (fn == "translate" || fn == "mirror" || fn == "scale"))
                v.c[2] = in.g->constant(fn == "scale" ? 1.0f : 0.0f), v.n = 3;
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
            case PT::Vec3:
                // material(color = field (p) -> [r, g, b]): a colour that varies with the point.
                if (info.id == Builtin::MaterialFn && std::string_view(p.name) == "color" && v.t == VT::Shape && v.shape->kind == ShapeKind::Field)
                    break;
                if (!(v.t == VT::Vector && v.n == 3)) bad("a 3-component vector");
                break;
            case PT::NumOrVec3: if (!(v.t == VT::Number || (v.t == VT::Vector && v.n == 3))) bad("a number or a 3-component vector"); break;
            case PT::NumOrVec2: if (!(v.t == VT::Number || (v.t == VT::Vector && v.n == 2))) bad("a number or a 2-component vector"); break;
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
    Vec3N vec2(size_t i) {  // [x, y] or a number for both; the third slot unused
        if (has(i)) {
            const Value& v = val(i);
            if (v.t == VT::Number) return {v.c[0], v.c[0], kNoNode};
            return {v.c[0], v.c[1], kNoNode};
        }
        require(i);
        const auto& d = info.params[i].def;
        return {in.g->constant(d[0]), in.g->constant(d[1]), kNoNode};
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

    // A shape's arguments by the Checks column of shapes.def. With `slots` (a primitive):
    // every stored parameter in order, its default where not given, appended. Without (an
    // operation, read again when applied): those given that have checks, and a missing
    // required one. First each argument's own finiteness and sign, then, once all are read,
    // ranges, whole numbers and directions.
    void read(std::vector<NodeId>* slots) {
        using namespace param_check;
        struct Later { size_t i; Vec3N v; int n; };
        std::vector<Later> later;
        for (size_t i = 0; i < info.params.size(); ++i) {
            const ParamSpec& p = info.params[i];
            if (slots ? !p.stored : !has(i) || !p.checks) {
                if (!slots) require(i);
                continue;
            }
            Vec3N v{kNoNode, kNoNode, kNoNode};
            int n = 1;
            if (p.type == PT::Num) v[0] = num(i);
            else if (p.type == PT::Bool) v[0] = boolean(i);
            else if (p.type == PT::Vec3 || p.type == PT::NumOrVec3) v = vec3(i), n = 3;
            else if (p.type == PT::NumOrVec2) v = vec2(i), n = 2;
            else in.fail(out.call_loc, fmt::format("internal: {} stores a parameter of no shape type", info.name));
            for (int k = 0; k < n; ++k) {
                if (p.checks & Finite) finite(v[k], i);
                if (p.checks & (NonNeg | Positive)) check_size(v[k], i, p.checks & Positive);
            }
            if (slots) slots->insert(slots->end(), v.begin(), v.begin() + n);
            if (p.checks & (Angle | Nonzero)) later.push_back({i, v, n});
        }
        for (const Later& l : later) {
            const ParamSpec& p = info.params[l.i];
            const NodeId x = l.v[0];
            if (p.checks & Angle) range(x, l.i, 0, 360);
            if (p.checks & Nonzero) {
                bool zero = true;
                for (int k = 0; k < l.n; ++k) zero &= in.g->is_const(l.v[k]) && in.g->const_value(l.v[k]) == 0.0f;
                if (zero) in.fail(loc(l.i), fmt::format("the {}'s {} must not be zero", info.name, p.name));
            }
        }
    }
};

void push3(std::vector<NodeId>& v, const Vec3N& a) { v.insert(v.end(), a.begin(), a.end()); }

// material()'s arguments over `base` (or the defaults): parameter 0 is the base itself,
// then one per script parameter of materials.def, a 3-vector or a size.
// (A colour field given for `color` is left to the caller: `field_rgb` receives it.)
MaterialN material_from(Interp& in, Binder& b, const MaterialN* base, ColorFn* field_rgb = nullptr) {
    MaterialN m = base ? *base : default_material(*in.g);
    size_t i = 0;
    for (int ch = 0; ch < kMatChannels; ++ch) {
        if (kMatChannelInfo[ch].component != 0) continue;  // a vector's later components
        if (!b.has(++i)) continue;
        if (b.val(i).t == VT::Shape) {
            if (field_rgb) *field_rgb = b.val(i).shape->field_rgb;
            continue;
        }
        if (b.info.params[i].type == PT::Vec3) {
            Vec3N v = b.vec3(i);
            for (int k = 0; k < 3; ++k) m[ch + k] = v[k];
        } else {
            m[ch] = b.size(i);
        }
    }
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
        Shape s{info.shape, loc};
        b.read(&s.params);
        if (s.kind == ShapeKind::Polygon) {
            // A list of at least 3 points [x, y], kept as x, y slots in turn.
            b.require(0);
            const Value& pts = b.val(0);
            if (pts.t != VT::List || !pts.list || pts.list->size() < 3)
                fail(b.loc(0), fmt::format("polygon takes a list of 3 or more points [x, y], not {}", describe(pts)));
            if (pts.list->size() > 100000) fail(b.loc(0), "polygon has more than 100000 points");
            for (size_t k = 0; k < pts.list->size(); ++k) {
                const Value& q = (*pts.list)[k];
                if (q.t != VT::Vector || q.n != 2)
                    fail(b.loc(0), fmt::format("polygon's point {} must be [x, y], not {}", k + 1, describe(q)));
                s.params.push_back(checked(q.c[0], b.loc(0)));
                s.params.push_back(checked(q.c[1], b.loc(0)));
            }
        }
        if (s.kind == ShapeKind::Cone) {  // 0/0 in the distance: a NaN naming no parameter
            bool all_zero = true;
            for (NodeId n : s.params) all_zero &= gr.is_const(n) && gr.const_value(n) == 0.0f;
            if (all_zero) fail(b.loc(0), "a cone needs a height h or a radius r1, r2 above zero (all three are 0)");
        }
        return Value::of_shape(make_shape(std::move(s)));
    }
    if (info.kind == BuiltinKind::Modifier) {
        auto m = std::make_shared<ModifierVal>();
        m->id = info.id;
        m->name = info.name;
        m->loc = loc;
        b.read(nullptr);  // validate eagerly so errors point at the call even before a target is seen
        m->args = std::make_shared<BoundArgs>(std::move(b.out));
        Value v;
        v.t = VT::Modifier, v.mod = m;
        return v;
    }
    if (info.kind == BuiltinKind::MaterialCtor) {
        MaterialN mat;
        if (info.id == B::Color) {
            b.require(0);  // (color() alone is no colour)
            mat = default_material(gr);
            if (b.has(0) && b.val(0).t == VT::Shape && b.val(0).shape->kind == ShapeKind::Field && b.val(0).shape->field_rgb) {
                // A colour that varies with the point: a modifier carrying the field's body.
                auto mv = std::make_shared<ModifierVal>();
                mv->id = B::Color;
                mv->name = "color";
                mv->loc = loc;
                mv->material = mat;
                mv->color_at = b.val(0).shape->field_rgb;
                Value v;
                v.t = VT::Modifier;
                v.mod = mv;
                return v;
            }
            if (b.has(0)) {
                const Value& c = b.val(0);
                if (c.t == VT::String) {
                    const Value rgb = colour_name(*c.str, b.loc(0));
                    for (int k = 0; k < 3; ++k) mat[kMatR + k] = rgb.c[k];
                } else {
                    if (c.t != VT::Vector || c.n < 3)
                        fail(b.loc(0), fmt::format("color takes [r, g, b] or a colour name such as \"tomato\", not {}", describe(c)));
                    for (int k = 0; k < 3; ++k) mat[kMatR + k] = c.c[k];
                    if (c.n == 4)
                        warn(b.loc(0), "color's alpha (the 4th component) is ignored: for see-through, "
                                                            "material(transparency = ...)");
                }
                if (b.has(1) && !(gr.is_const(b.val(1).c[0]) && gr.const_value(b.val(1).c[0]) == 1.0f))
                    warn(b.loc(1), "color's alpha is ignored: for see-through, material(transparency = ...)");
            } else {
                // `color` with no argument only makes sense applied; use the default.
            }
        } else {
            const MaterialN* base = b.has(0) ? b.val(0).mat.get() : nullptr;
            ColorFn field_rgb;
            mat = material_from(*this, b, base, &field_rgb);
            if (field_rgb) {  // a modifier, as color(field ...) is
                auto mv = std::make_shared<ModifierVal>();
                mv->id = B::MaterialFn;
                mv->name = "material";
                mv->loc = loc;
                mv->material = mat;
                mv->color_at = field_rgb;
                Value v;
                v.t = VT::Modifier;
                v.mod = mv;
                return v;
            }
        }
        Value v;
        v.t = VT::Material;
        v.mat = std::make_shared<const MaterialN>(mat);
        return v;
    }
    // Settings
    note_setting_in_target(info, loc);
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
            r.samples = whole(2, 1, 4096);  // (as --samples and the API)
            r.max_steps = whole(3, 1, 100000);
            r.max_distance = const_num(Value::number(b.size(4, true)), b.loc(4), "max_distance");
            r.max_distance_set = b.has(4);
            r.epsilon = const_num(Value::number(b.size(5, true)), b.loc(5), "epsilon");
            r.shadows = const_num(Value::number(b.boolean(6)), b.loc(6), "shadows") != 0;
            r.ao = const_num(Value::number(b.boolean(7)), b.loc(7), "ao") != 0;
            r.max_bounces = whole(8, 0, 64);
            if (b.has(9)) {
                const std::string& aa = *b.val(9).str;
                if (aa != "grid" && aa != "cone") fail(b.loc(9), fmt::format("aa must be \"grid\" or \"cone\", not \"{}\"", aa));
                r.aa = aa;
            }
            if (b.has(10)) {
                r.exposure = const_num(b.val(10), b.loc(10), "exposure");
                if (!(r.exposure > 0.0f) || !std::isfinite(r.exposure))
                    fail(b.loc(10), fmt::format("render exposure must be a number above 0, not {}", r.exposure));
            }
            if (b.has(11)) {
                const std::string& tm = *b.val(11).str;
                if (tm != "none" && tm != "reinhard" && tm != "aces")
                    fail(b.loc(11), fmt::format("tonemap must be \"none\", \"reinhard\" or \"aces\", not \"{}\"", tm));
                r.tonemap = tm;
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
        // iterations as operands instead (the same union, and smooth ones blend them), and
        // so do the intersections whose only operand it is (OpenSCAD's intersection_for).
        s.kind = k;
        if (target->kind == ShapeKind::Union && !target->iterations && !target->children.empty()) s.children = target->children;
        else s.children = {target};
        const bool union_like = k == ShapeKind::Union || k == ShapeKind::SmoothUnion || k == ShapeKind::ChamferUnion ||
                                k == ShapeKind::StairsUnion;
        const bool meets = k == ShapeKind::Intersection || k == ShapeKind::SmoothIntersection || k == ShapeKind::ChamferIntersection ||
                           k == ShapeKind::StairsIntersection;
        if ((union_like || (meets && s.children.size() == 1)) && std::any_of(s.children.begin(), s.children.end(), [](const ShapePtr& c) { return c->iterations; })) {
            std::vector<ShapePtr> flat;
            for (const ShapePtr& c : s.children) {
                if (c->iterations) flat.insert(flat.end(), c->children.begin(), c->children.end());
                else flat.push_back(c);
            }
            s.children = std::move(flat);
        }
        // Legal, but likely not what was meant.
        const std::string_view op = m.name;
        const bool cut = op.find("difference") != std::string_view::npos;
        const bool meet = op.find("intersection") != std::string_view::npos;
        const bool empty = s.children.size() == 1 && (s.children[0]->kind == ShapeKind::Empty || (s.children[0]->kind == ShapeKind::Union && s.children[0]->children.empty()));
        if ((cut || meet) && empty)
            warn(m.loc, fmt::format("this {} has no operands: it is empty", m.name));
        else if (cut && s.children.size() == 1)
            warn(m.loc, fmt::format("this {} has one operand: it cuts nothing away (a second shape is missing?)", m.name));
        else if (meet && s.children.size() == 1)
            warn(m.loc, fmt::format("this {} has one operand: it is that shape (a second shape is missing?)", m.name));
        // An if whose condition is false, or a for without iterations, is an empty operand:
        // as the first of a difference, or in an intersection, it empties the whole.
        const auto none = [](const ShapePtr& c) { return c->kind == ShapeKind::Empty || (c->kind == ShapeKind::Union && c->children.empty()); };
        const auto last = cut && s.children.size() > 1 ? s.children.begin() + 1 : s.children.end();  // (a difference: its first)
        const auto hit = std::find_if(s.children.begin(), last, none);
        if ((cut || meet) && s.children.size() > 1 && hit != last)
            warn((*hit)->loc, fmt::format("this operand of the {} adds no shape (a false condition, a loop without iterations): the {} is empty", m.name, m.name));
    };
    switch (m.id) {
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
        case B::Mirror: {
            s.kind = ShapeKind::Mirror;
            Vec3N n = v3(0, 0);
            NodeId len = gr.binary(Op::Max, gr.ternary(Op::Length3, n[0], n[1], n[2]), gr.constant(1e-30f));  // 0: no mirror (OpenSCAD)
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
        case B::MaterialFn:
        case B::Color:
            s.kind = ShapeKind::Material;
            s.material = m.material;
            s.color_at = m.color_at;
            s.children = {target};
            break;
        default: {
            // A Table row of shapes.def: its parameters as given, in order.
            const BuiltinInfo& info = builtin_info(m.id);
            if (info.kind != BuiltinKind::Modifier || info.build != ShapeBuild::Table)
                fail(loc, fmt::format("internal: {} is not an operation", m.name));
            if (shape_family(info.shape) == ShapeFamily::Csg) {
                csg(info.shape);
            } else {
                s.kind = info.shape;
                s.children = {target};
            }
            for (size_t i = 0; i < info.params.size(); ++i) {
                const ParamSpec& p = info.params[i];
                if (!p.stored) continue;
                if (p.type == PT::Num) s.params.push_back(arg(i) ? num(*arg(i), a.locs[i], "argument") : gr.constant(p.def[0]));
                else if (p.type == PT::Bool) s.params.push_back(arg(i) ? truth(*arg(i), a.locs[i]) : gr.constant(p.def[0]));
                else push3(s.params, arg(i) ? vec3(*arg(i), a.locs[i], "argument", true)
                                            : Vec3N{gr.constant(p.def[0]), gr.constant(p.def[1]), gr.constant(p.def[2])});
            }
        }
    }
    return make_shape(std::move(s));
}

}  // namespace sdfc
