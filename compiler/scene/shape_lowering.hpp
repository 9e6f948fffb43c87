// Internal to compiler/scene: what the shape family files (shapes_primitives.cpp,
// shapes_csg.cpp, shapes_modifiers.cpp) share. The lowering context L (IR helpers on
// 3-vectors of nodes), the bounds helpers, and one lower_Kind / bounds_Kind pair per row of
// shapes.def, which lower.cpp dispatches to.
#pragma once
#include <cmath>
#include <numbers>
#include <vector>

#include "compiler/scene/lower.hpp"

namespace sdfc::shapes {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kDeg = kPi / 180.0f;

struct L {  // lowering context: graph + helpers on 3-vectors of nodes
    Graph& g;
    // Primitives only: the constants 0.5 and 0, made (in this order) before each primitive's
    // formula, as they always were: the IR numbers its nodes in the order they are made.
    NodeId half = kNoNode, zero = kNoNode;
    NodeId c(float v) { return g.constant(v); }
    NodeId add(NodeId a, NodeId b) { return g.add(a, b); }
    NodeId sub(NodeId a, NodeId b) { return g.sub(a, b); }
    NodeId mul(NodeId a, NodeId b) { return g.mul(a, b); }
    NodeId div(NodeId a, NodeId b) { return g.div(a, b); }
    NodeId mn(NodeId a, NodeId b) { return g.min(a, b); }
    NodeId mx(NodeId a, NodeId b) { return g.max(a, b); }
    NodeId abs(NodeId a) { return g.abs(a); }
    NodeId neg(NodeId a) { return g.neg(a); }
    NodeId sq(NodeId a) { return g.unary(Op::Square, a); }
    NodeId sqrt(NodeId a) { return g.sqrt(a); }
    NodeId clamp(NodeId x, NodeId lo, NodeId hi) { return g.clamp(x, lo, hi); }
    NodeId len2(NodeId a, NodeId b) { return g.binary(Op::Length2, a, b); }
    NodeId len3(NodeId a, NodeId b, NodeId d) { return g.ternary(Op::Length3, a, b, d); }
    NodeId sel(NodeId cnd, NodeId a, NodeId b) { return g.select(cnd, a, b); }
    NodeId lt(NodeId a, NodeId b) { return g.binary(Op::Lt, a, b); }
    NodeId dot3(const Vec3N& a, const Vec3N& b) { return add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2])); }
    Vec3N sub3(const Vec3N& a, const Vec3N& b) { return {sub(a[0], b[0]), sub(a[1], b[1]), sub(a[2], b[2])}; }
    Vec3N abs3(const Vec3N& a) { return {abs(a[0]), abs(a[1]), abs(a[2])}; }
    NodeId maxcomp(const Vec3N& a) { return mx(a[0], mx(a[1], a[2])); }
    // Exact box distance from q = |p| - half: length(max(q,0)) + min(maxcomp(q), 0)
    NodeId box_q(const Vec3N& q) {
        NodeId z = c(0);
        return add(len3(mx(q[0], z), mx(q[1], z), mx(q[2], z)), mn(maxcomp(q), z));
    }
    NodeId box2_q(NodeId qx, NodeId qy) {
        NodeId z = c(0);
        return add(len2(mx(qx, z), mx(qy, z)), mn(mx(qx, qy), z));
    }
};

// A parameter by its slot (SphereP::r), a vector by its first slot.
inline NodeId P(const Shape& s, size_t i) { return s.params.at(i); }
inline Vec3N P3(const Shape& s, size_t i) { return {s.params.at(i), s.params.at(i + 1), s.params.at(i + 2)}; }

// Normalised child distance (1-Lipschitz).
inline NodeId unit(Graph& g, const Lowered& l) { return l.lip == 1.0f ? l.d : g.mulc(l.d, 1.0f / l.lip); }

MaterialN mix_mat(Graph& g, const MaterialN& a, const MaterialN& b, NodeId t);
MaterialN select_mat(Graph& g, NodeId cond, const MaterialN& a, const MaterialN& b);

// The nearer of two lowered shapes with the same Lipschitz bound (a's on ties), with its
// material when materials are lowered.
Lowered nearer(L& l, const Lowered& a, const Lowered& b, bool materials);

// What a bounds_Kind function reads: the shape, its parameters as constants (lower.cpp
// answers infinite bounds for a shape with any other), its children's bounds.
struct BoundsIn {
    const Graph& g;
    const Shape& s;
    std::vector<float> v;
    float f(size_t i) const { return std::fabs(v.at(i)); }
    glm::vec3 v3(size_t i) const { return glm::vec3(v.at(i), v.at(i + 1), v.at(i + 2)); }
    Bounds child(size_t i = 0) const { return shape_bounds(g, *s.children.at(i)); }
};

constexpr float kInf = 1e30f;
inline Bounds infinite() { return Bounds{}; }
inline Bounds empty() { return Bounds{glm::vec3(kInf), glm::vec3(-kInf)}; }
inline Bounds sym(glm::vec3 e) { return Bounds{-e, e}; }
inline Bounds grow(Bounds b, float r) {
    for (int i = 0; i < 3; ++i) {
        if (b.lo[i] > -kInf * 0.1f) b.lo[i] -= r;
        if (b.hi[i] < kInf * 0.1f) b.hi[i] += r;
    }
    return b;
}
inline Bounds join(const Bounds& a, const Bounds& b) { return Bounds{glm::min(a.lo, b.lo), glm::max(a.hi, b.hi)}; }
inline Bounds meet(const Bounds& a, const Bounds& b) { return Bounds{glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)}; }
// The box around a finite box mapped by p -> m p + t (its 8 corners).
inline Bounds mapped_box(const Bounds& c, const glm::mat3& m, const glm::vec3& t = glm::vec3(0.0f)) {
    Bounds out = empty();
    for (int i = 0; i < 8; ++i) {
        const glm::vec3 q = m * glm::vec3{i & 1 ? c.hi.x : c.lo.x, i & 2 ? c.hi.y : c.lo.y, i & 4 ? c.hi.z : c.lo.z} + t;
        out = join(out, Bounds{q, q});
    }
    return out;
}
// A rotation's matrix (world = m * local) from its 9 row-major entries (RotateP::m).
template <class Entry>
glm::mat3 rotation_rows(Entry entry) {
    glm::mat3 m(1.0f);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m[c][r] = entry(size_t(r) * 3 + size_t(c));
    return m;
}
inline bool is_empty(const Bounds& b) { return b.lo.x > b.hi.x || b.lo.y > b.hi.y || b.lo.z > b.hi.z; }

// One pair per row of shapes.def. A primitive returns its distance and Lipschitz bound (the
// dispatcher adds the inherited material); the others lower their children themselves.
#define SDFC_LOWER_Primitive(kind) Lowered lower_##kind(L& l, const Shape& s, const Vec3N& p);
#define SDFC_LOWER_Csg(kind) Lowered lower_##kind(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited);
#define SDFC_LOWER_Modifier(kind) SDFC_LOWER_Csg(kind)
#define SDFC_SHAPE(kind, name, family, ...) SDFC_LOWER_##family(kind) Bounds bounds_##kind(const BoundsIn& b);
#define SDFC_INNER_SHAPE(kind, family, ...) SDFC_LOWER_##family(kind) Bounds bounds_##kind(const BoundsIn& b);
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
#undef SDFC_LOWER_Primitive
#undef SDFC_LOWER_Csg
#undef SDFC_LOWER_Modifier

}  // namespace sdfc::shapes
