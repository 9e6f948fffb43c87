// Shape tree -> IR, and shape bounds: the dispatch over the rows of shapes.def. Each kind's
// distance, Lipschitz bound and bounding box sit side by side in its family's file
// (shapes_primitives.cpp, shapes_csg.cpp, shapes_modifiers.cpp).
#include "compiler/scene/lower.hpp"

#include <fmt/format.h>

#include "compiler/scene/shape_lowering.hpp"

namespace sdfc {

namespace shapes {

MaterialN mix_mat(Graph& g, const MaterialN& a, const MaterialN& b, NodeId t) {
    MaterialN m;
    for (int i = 0; i < kMatChannels; ++i) m[i] = g.mix(a[i], b[i], t);
    return m;
}

MaterialN select_mat(Graph& g, NodeId cond, const MaterialN& a, const MaterialN& b) {
    MaterialN m;
    for (int i = 0; i < kMatChannels; ++i) m[i] = g.select(cond, a[i], b[i]);
    return m;
}

Lowered nearer(L& l, const Lowered& a, const Lowered& b, bool materials) {
    Lowered r{l.mn(a.d, b.d), a.lip, {}};
    if (materials) r.m = select_mat(l.g, l.lt(a.d, b.d), a.m, b.m);
    return r;
}

}  // namespace shapes

using namespace shapes;

NodeId lower_distance(Graph& g, const Shape& shape, const Vec3N& p) {
    Lowered r = lower_shape(g, shape, p, nullptr);
    return unit(g, r);
}

Lowered lower_shape(Graph& g, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    check_stack(s.loc);
    // (A polygon's slots are its points': two each, three points or more.)
    const bool slots_ok = s.kind == ShapeKind::Polygon ? s.params.size() >= 6 && s.params.size() % 2 == 0 : s.params.size() == shape_slots(s.kind);
    if (!slots_ok)
        throw CompileError(s.loc, fmt::format("internal: {} has {} parameters, not {}", shape_kind_name(s.kind),
                                              s.params.size(), shape_slots(s.kind)));
    Loc saved = g.loc();
    if (s.loc.known()) g.set_loc(s.loc);
    // A union's threshold (guards, GuardRegion) reaches unions below it through modifiers
    // that move shapes rigidly or colour them; anything else changes what distances mean.
    const Graph::GuardContext guards = g.guard_context();
    const bool rigid = s.kind == ShapeKind::Union || s.kind == ShapeKind::Translate || s.kind == ShapeKind::Rotate ||
                       s.kind == ShapeKind::Mirror || s.kind == ShapeKind::Material;
    if (!rigid) g.set_guard_context({kNoNode, guards.region});
    L l{g};
    Lowered out;
    switch (s.kind) {
#define SDFC_CALL_Primitive(kind)                     \
    l.half = l.c(0.5f);                               \
    l.zero = l.c(0);                                  \
    out = lower_##kind(l, s, p);                      \
    if (inherited) out.m = *inherited;
#define SDFC_CALL_Csg(kind) out = lower_##kind(l, s, p, inherited);
#define SDFC_CALL_Modifier(kind) out = lower_##kind(l, s, p, inherited);
#define SDFC_SHAPE(kind, name, family, ...) case ShapeKind::kind: { SDFC_CALL_##family(kind) break; }
#define SDFC_INNER_SHAPE(kind, family, ...) case ShapeKind::kind: { SDFC_CALL_##family(kind) break; }
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
#undef SDFC_CALL_Primitive
#undef SDFC_CALL_Csg
#undef SDFC_CALL_Modifier
    }
    g.set_guard_context(guards);
    g.set_loc(saved);
    return out;
}

Bounds shape_bounds(const Graph& g, const Shape& s) {
    check_stack(s.loc);
    // Every parameter must be a constant for a finite answer.
    BoundsIn in{g, s, {}};
    for (NodeId n : s.params) {
        if (!g.is_const(n)) {
            // A rotation about the origin by an angle that varies (time, a param) keeps the
            // child within its radius of the origin.
            if (s.kind != ShapeKind::Rotate) return infinite();
            const Bounds c = shape_bounds(g, *s.children.at(0));
            if (is_empty(c) || !c.finite()) return c;
            return sym(glm::vec3(glm::length(glm::max(glm::abs(c.lo), glm::abs(c.hi)))));
        }
        in.v.push_back(g.const_value(n));
    }
    switch (s.kind) {
#define SDFC_SHAPE(kind, ...) case ShapeKind::kind: return bounds_##kind(in);
#define SDFC_INNER_SHAPE(kind, ...) case ShapeKind::kind: return bounds_##kind(in);
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
    }
    return infinite();
}

namespace {

// clip_regions of a shape placed by a similarity: world = r * local + t, r a rotation times
// a uniform scale; every region grown by `grow` (world units: the blends around it).
bool clip_placed(const Graph& g, const Shape& s, const glm::mat3& r, const glm::vec3& t, float grow, Bounds& box,
                 std::vector<glm::vec4>& half_spaces) {
    check_stack(s.loc);
    auto constant = [&] {
        for (NodeId n : s.params)
            if (!g.is_const(n)) return false;
        return true;
    };
    switch (s.kind) {
        case ShapeKind::Union:
            for (const auto& c : s.children)
                if (!clip_placed(g, *c, r, t, grow, box, half_spaces)) return false;
            return true;
        case ShapeKind::SmoothUnion:
        case ShapeKind::ChamferUnion:
        case ShapeKind::StairsUnion: {  // (a blend adds at most its radius around the union: their bounds' rule)
            if (!constant()) break;
            const float k = g.const_value(s.params.at(0));
            if (!(k >= 0.0f) || !std::isfinite(k)) break;
            for (const auto& c : s.children)
                if (!clip_placed(g, *c, r, t, grow + k * glm::length(r[0]), box, half_spaces)) return false;
            return true;
        }
        case ShapeKind::Material: return s.children.empty() || clip_placed(g, *s.children[0], r, t, grow, box, half_spaces);
        case ShapeKind::Translate: {  // (a floor is often placed so: translate([0, -1, 0]) plane())
            if (!constant() || s.children.empty()) break;
            const Vec3N v = P3(s, TranslateP::v);
            const glm::vec3 d(g.const_value(v[0]), g.const_value(v[1]), g.const_value(v[2]));
            return clip_placed(g, *s.children[0], r, t + r * d, grow, box, half_spaces);
        }
        case ShapeKind::Rotate: {
            if (!constant() || s.children.empty()) break;
            const glm::mat3 m = rotation_rows([&](size_t k) { return g.const_value(s.params.at(RotateP::m + k)); });
            return clip_placed(g, *s.children[0], r * m, t, grow, box, half_spaces);
        }
        case ShapeKind::Scale: {  // uniform only: a plane stays a plane (scale(25.4) { ...; plane(); })
            if (!constant() || s.children.empty()) break;
            const Vec3N v = P3(s, ScaleP::s);
            const float k = g.const_value(v[0]);
            if (!(k > 0.0f) || !std::isfinite(k) || g.const_value(v[1]) != k || g.const_value(v[2]) != k) break;
            return clip_placed(g, *s.children[0], r * k, t, grow, box, half_spaces);
        }
        case ShapeKind::Plane: {
            if (!constant()) return false;
            const Vec3N pn = P3(s, PlaneP::normal);
            const glm::vec3 n(g.const_value(pn[0]), g.const_value(pn[1]), g.const_value(pn[2]));
            const float len = glm::length(n), h = g.const_value(P(s, PlaneP::offset));
            if (!(len > 0.0f) || !std::isfinite(len) || !std::isfinite(h)) return false;
            // n.q <= h for q = r^-1 (p - t), r = k R: (R n).p <= k h + (R n).t
            const float k = glm::length(r[0]);
            const glm::vec3 wn = r * (n / len) / k;
            const float w = k * h + glm::dot(wn, t) + grow;
            if (!std::isfinite(w)) return false;
            half_spaces.emplace_back(wn, w);
            return true;
        }
        default: break;
    }
    const Bounds b = shape_bounds(g, s);
    if (is_empty(b)) return true;
    if (!b.finite()) return false;
    box = join(box, ::sdfc::grow(mapped_box(b, r, t), grow));
    return true;
}

}  // namespace

bool clip_regions(const Graph& g, const Shape& s, Bounds& box, std::vector<glm::vec4>& half_spaces) {
    return clip_placed(g, s, glm::mat3(1.0f), glm::vec3(0.0f), 0.0f, box, half_spaces);
}

}  // namespace sdfc
