// The CSG operations of shapes.def (LANGUAGE.md section 6) and Choose: how each combines
// two distances (and which material shows), then its bounding box. Formulas follow Inigo
// Quilez and hg_sdf (mercury.sexy/hg_sdf). Children are divided by their Lipschitz bound
// first, so one distorting modifier does not make the whole scene conservative.
#include <algorithm>
#include <cmath>
#include <optional>

#include "compiler/scene/shape_lowering.hpp"

namespace sdfc::shapes {

namespace {

// One step of a CSG fold: the combined distance, and either the condition under which the
// accumulated operand's material shows or the weight of the new operand's (smooth blends).
struct Step {
    NodeId d;
    NodeId closer_a = kNoNode;
    NodeId blend = kNoNode;
};

// The children combined left to right by `step(a, b)` (both 1-Lipschitz).
template <class F>
Lowered fold(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited, F step) {
    Graph& g = l.g;
    if (s.children.empty()) return Lowered{l.c(1e20f), 1.0f, inherited ? *inherited : MaterialN{}};
    Lowered acc = lower_shape(g, *s.children[0], p, inherited);
    acc.d = unit(g, acc);
    acc.lip = 1.0f;
    for (size_t i = 1; i < s.children.size(); ++i) {
        Lowered c = lower_shape(g, *s.children[i], p, inherited);
        NodeId a = acc.d, b = unit(g, c);
        Step r = step(a, b);
        if (inherited) {
            if (r.blend != kNoNode)
                acc.m = mix_mat(g, acc.m, c.m, r.blend);
            else
                acc.m = select_mat(g, r.closer_a, acc.m, c.m);
        }
        acc.d = r.d;
    }
    return acc;
}

// Bounds of the union-like operations: the children's, grown by the blend radius.
Bounds joined(const BoundsIn& b, float r) {
    Bounds u = empty();
    for (size_t i = 0; i < b.s.children.size(); ++i) u = join(u, b.child(i));
    return is_empty(u) ? u : grow(u, r);
}
Bounds met(const BoundsIn& b) {
    Bounds u = infinite();
    for (size_t i = 0; i < b.s.children.size(); ++i) u = meet(u, b.child(i));
    return u;
}
Bounds first(const BoundsIn& b) { return b.s.children.empty() ? empty() : b.child(0); }

// A plain union of many bounded shapes, as a balanced tree of min() over the children in
// space order (recursive median splits of their bounds' centres on the widest axis: a k-d
// tree). The same distance as the script's chain (min is exact and associative), but over
// a box, interval arithmetic (runtime/eval/interval.hpp) decides a whole far subtree at its
// root, so the tracer's per-cell programs keep only the shapes near the cell: with a chain
// in script order (say a for loop over a grid) the running minimum approaches a box a
// little at a time and every shape about as far as it stays. Measured on a 100 x 100 grid
// of spheres, a 0.5-unit box keeps 502 of 30,203 instructions instead of 4,857. With an
// unbounded child (a floor plane) the chain stays: the plane's bound, first in the chain,
// prunes far shapes at once, which no inner node of a tree would see (measured: worse
// tapes on examples/showcase.sdf). Ties between equally near shapes may pick another
// child's material than the chain would. Returns nothing to keep the chain.
constexpr size_t kSpatialUnion = 8;

// Guards (compiler/ir/ir.hpp GuardRegion): a union's child of at least kGuardMinShapes shapes
// (or a k-d subtree of them) becomes a region that evaluators may skip where the point is
// farther from its box than the union's distance without it (`thr`). Smaller children are
// cheaper to compute than to guard.
constexpr size_t kGuardMinShapes = 8;

// Whether the shape's distance is never below the distance to its bounding box
// (shape_bounds), outside it: then skipping it there changes no union's value, and the
// renderers that skip (the GLSL tape interpreter) draw what those that do not draw. True
// for exact distances, and for what keeps them so with bounds grown to match (round,
// onion, smooth and chamfer unions: below the hard union by at most their blend, bounds
// grown by it; a difference: at least its first shape's). Not for bounds that are loose
// (twist, bend, non-uniform scale, ellipsoid, a custom field: distances divided by a
// Lipschitz bound), nor intersections (the box of the overlap is farther than either).
bool exact_outside_box(const Graph& g, const Shape& s) {
    auto all = [&](size_t from) {
        for (size_t i = from; i < s.children.size(); ++i)
            if (!exact_outside_box(g, *s.children[i])) return false;
        return !s.children.empty();
    };
    switch (s.kind) {
        case ShapeKind::Sphere: case ShapeKind::Box: case ShapeKind::RoundBox: case ShapeKind::BoxFrame: case ShapeKind::Torus:
        case ShapeKind::CappedTorus: case ShapeKind::Link: case ShapeKind::Cylinder: case ShapeKind::RoundCylinder:
        case ShapeKind::Capsule: case ShapeKind::Cone: case ShapeKind::Octahedron: case ShapeKind::Pyramid:
        case ShapeKind::HexPrism: case ShapeKind::Empty:
            return true;
        case ShapeKind::Union: case ShapeKind::SmoothUnion: case ShapeKind::ChamferUnion:
        case ShapeKind::Translate: case ShapeKind::Rotate: case ShapeKind::Mirror: case ShapeKind::Material:
        case ShapeKind::Round: case ShapeKind::Onion:
            return all(0);
        case ShapeKind::Difference: return !s.children.empty() && exact_outside_box(g, *s.children[0]);
        case ShapeKind::Scale: {
            const Vec3N v = P3(s, ScaleP::s);
            for (NodeId n : v)
                if (!g.is_const(n) || g.const_value(n) != g.const_value(v[0])) return false;
            return all(0);
        }
        default: return false;
    }
}

// The child lowered at p, made 1-Lipschitz, in a region of its own when `thr` is a node and
// the child is worth it. Unions inside it (through rigid modifiers) see `thr` as theirs.
Lowered lower_child(L& l, const Shape& c, const Vec3N& p, const MaterialN* inherited, NodeId thr, const Bounds* box) {
    Graph& g = l.g;
    const Graph::GuardContext outer = g.guard_context();
    Bounds b = box ? *box : Bounds{};
    const bool guarded = thr != kNoNode && c.tree_size >= kGuardMinShapes && (box || (b = shape_bounds(g, c), true)) && b.finite() &&
                         !is_empty(b) && exact_outside_box(g, c);
    int32_t id = -1;
    if (guarded) {
        GuardRegion r;
        r.thr = thr;
        for (int i = 0; i < 3; ++i) r.point[i] = p[size_t(i)], r.lo[i] = b.lo[i], r.hi[i] = b.hi[i];
        r.parent = outer.region;
        id = g.add_guard(r);
    }
    g.set_guard_context({guarded ? thr : kNoNode, guarded ? id : outer.region});
    Lowered out = lower_shape(g, c, p, inherited);
    out.d = unit(g, out);
    out.lip = 1.0f;
    g.set_guard_context(outer);
    if (guarded) {
        GuardRegion& r = g.guard(id);
        r.root = out.d;
        if (inherited) r.extra.assign(out.m.begin(), out.m.end());
    }
    return out;
}

// A plain union of many bounded shapes, as a balanced tree of min() over the children in
// space order (recursive median splits of their bounds' centres on the widest axis: a k-d
// tree). The same distance as the script's chain (min is exact and associative), but over
// a box, interval arithmetic (runtime/eval/interval.hpp) decides a whole far subtree at its
// root, so the tracer's per-cell programs keep only the shapes near the cell: with a chain
// in script order (say a for loop over a grid) the running minimum approaches a box a
// little at a time and every shape about as far as it stays. Measured on a 100 x 100 grid
// of spheres, a 0.5-unit box keeps 502 of 30,203 instructions instead of 4,857. With an
// unbounded child (a floor plane) the chain stays: the plane's bound, first in the chain,
// prunes far shapes at once, which no inner node of a tree would see (measured: worse
// tapes on examples/showcase.sdf). Ties between equally near shapes may pick another
// child's material than the chain would. Subtrees of kGuardMinShapes shapes or more are
// guarded regions (the right one against the left's distance, both against the union's
// threshold). Returns nothing to keep the chain.
std::optional<Lowered> lower_union_spatial(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Graph& g = l.g;
    std::vector<Bounds> bounds(s.children.size());
    std::vector<glm::vec3> centre(s.children.size());
    std::vector<uint8_t> exact(s.children.size());
    for (size_t i = 0; i < s.children.size(); ++i) exact[i] = exact_outside_box(g, *s.children[i]);
    for (size_t i = 0; i < s.children.size(); ++i) {
        const Bounds b = shape_bounds(g, *s.children[i]);
        if (!(b.finite() && b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) return std::nullopt;
        bounds[i] = b;
        centre[i] = 0.5f * (b.lo + b.hi);
    }
    std::vector<uint32_t> order(s.children.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<uint32_t>(i);
    // Shapes under [first, last), or 0 when one of them may not be skipped (exact_outside_box).
    auto shapes = [&](const uint32_t* first, const uint32_t* last) {
        size_t n = 0;
        for (const uint32_t* i = first; i != last; ++i) {
            if (!exact[*i]) return size_t(0);
            n += s.children[*i]->tree_size;
        }
        return n;
    };
    // The subtree over [first, last) against threshold thr (kNoNode: none).
    auto build = [&](auto&& self, uint32_t* first, uint32_t* last, NodeId thr) -> Lowered {
        if (last - first == 1) return lower_child(l, *s.children[*first], p, inherited, thr, &bounds[*first]);
        const size_t n = shapes(first, last);
        const Graph::GuardContext outer = g.guard_context();
        int32_t id = -1;
        if (thr != kNoNode && n >= kGuardMinShapes) {
            GuardRegion r;
            r.thr = thr;
            Bounds b = empty();
            for (const uint32_t* i = first; i != last; ++i) b = join(b, bounds[*i]);
            for (int i = 0; i < 3; ++i) r.point[i] = p[size_t(i)], r.lo[i] = b.lo[i], r.hi[i] = b.hi[i];
            r.parent = outer.region;
            id = g.add_guard(r);
            g.set_guard_context({thr, id});
        }
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (const uint32_t* i = first; i != last; ++i) lo = glm::min(lo, centre[*i]), hi = glm::max(hi, centre[*i]);
        const glm::vec3 ext = hi - lo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        // Deterministic: ties in a coordinate keep the children's order.
        std::stable_sort(first, last, [&](uint32_t a, uint32_t b) { return centre[a][axis] < centre[b][axis]; });
        uint32_t* mid = first + (last - first) / 2;
        const Lowered a = self(self, first, mid, thr);  // in this order: node numbering
        NodeId thr_b = kNoNode;
        if (shapes(mid, last) >= kGuardMinShapes) thr_b = thr == kNoNode ? a.d : g.min(thr, a.d);
        const Lowered b = self(self, mid, last, thr_b);
        Lowered r = nearer(l, a, b, inherited);
        g.set_guard_context(outer);
        if (id >= 0) {
            GuardRegion& gr = g.guard(id);
            gr.root = r.d;
            if (inherited) gr.extra.assign(r.m.begin(), r.m.end());
        }
        return r;
    };
    return build(build, order.data(), order.data() + order.size(), g.guard_context().thr);
}

}  // namespace

// --- hard operations

// The chain of children in the script's order, but for the big ones (kGuardMinShapes shapes
// or more), which come last: each is guarded against the chain's distance so far (and the
// union's own threshold), so the small ones (a floor plane) make that distance first.
// (Only ties between equally near shapes can show the difference, in their material.)
Lowered lower_Union(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    if (!s.children.empty() && s.children.size() >= kSpatialUnion)
        if (std::optional<Lowered> t = lower_union_spatial(l, s, p, inherited)) return *t;
    Graph& g = l.g;
    if (s.children.empty()) return Lowered{l.c(1e20f), 1.0f, inherited ? *inherited : MaterialN{}};
    std::vector<const Shape*> order;
    for (const ShapePtr& c : s.children)
        if (c->tree_size < kGuardMinShapes) order.push_back(c.get());
    for (const ShapePtr& c : s.children)
        if (c->tree_size >= kGuardMinShapes) order.push_back(c.get());
    const NodeId outer = g.guard_context().thr;
    Lowered acc = lower_child(l, *order[0], p, inherited, outer, nullptr);
    for (size_t i = 1; i < order.size(); ++i) {
        const Shape& c = *order[i];
        NodeId thr = kNoNode;
        if (c.tree_size >= kGuardMinShapes) thr = outer == kNoNode ? acc.d : g.min(outer, acc.d);
        const Lowered b = lower_child(l, c, p, inherited, thr, nullptr);
        const NodeId d = l.mn(acc.d, b.d);
        if (inherited) acc.m = select_mat(g, l.lt(acc.d, b.d), acc.m, b.m);
        acc.d = d;
    }
    return acc;
}
Bounds bounds_Union(const BoundsIn& b) { return joined(b, 0.0f); }

Lowered lower_Intersection(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId d = l.mx(a, b);
        return Step{d, l.lt(b, a)};
    });
}
Bounds bounds_Intersection(const BoundsIn& b) { return met(b); }

Lowered lower_Difference(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId d = l.mx(a, l.neg(b));
        return Step{d, l.lt(l.neg(b), a)};
    });
}
Bounds bounds_Difference(const BoundsIn& b) { return first(b); }

Lowered lower_Xor(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId d = l.mx(l.mn(a, b), l.neg(l.mx(a, b)));
        return Step{d, l.lt(a, b)};
    });
}
Bounds bounds_Xor(const BoundsIn& b) { return joined(b, 0.0f); }

// --- smooth operations: quadratic polynomial smooth min (Quilez), equal to the hard
// operation where |a - b| >= k. Intersection and difference are the union of negations.

namespace {
enum class Sides { Union, Intersection, Difference };
constexpr size_t kSelectedBlends = 8;  // operands from which a blend is a select (below)

Lowered smooth(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited, Sides op) {
    static_assert(SmoothUnionP::k == 0 && SmoothIntersectionP::k == 0 && SmoothDifferenceP::k == 0);
    Graph& g = l.g;
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        Step r{kNoNode};
        NodeId sa = a, sb = b;
        if (op == Sides::Intersection) { sa = l.neg(a); sb = l.neg(b); }
        if (op == Sides::Difference) { sa = l.neg(a); sb = b; }
        if (g.is_const(P(s, 0)) && g.const_value(P(s, 0)) <= 0.0f) {
            r.d = l.mn(sa, sb);
            r.closer_a = l.lt(sa, sb);
        } else {
            NodeId k = P(s, 0);
            // A k known only when the program runs (time, a param) may reach 0 or below: the
            // divisor stays above 0, so h is 0 there and the blend the hard operation (0 / 0
            // was NaN in the shader, which drew nothing).
            const NodeId kd = g.is_const(k) ? k : l.mx(k, l.c(1e-30f));
            NodeId h = l.div(l.mx(l.sub(k, l.abs(l.sub(sa, sb))), l.c(0)), kd);
            r.d = l.sub(l.mn(sa, sb), l.mul(l.mul(l.sq(h), k), l.c(0.25f)));
            // Many operands: the same floats (h is 0 where gap >= k) as a select, so that where
            // intervals prove the operands k apart the blend's code is dropped whole and a far
            // operand costs nothing in a pruned tape; without it each left 6 instructions
            // computing 0 (a smooth_union of 5,000 spheres: leaves' tapes 56,109 of 68,290
            // instructions, now 1,471 of 78,289). Two more instructions an operand, so not for
            // the usual few (showcase.sdf 1.06x the time, csg-tori.sdf 1.05x).
            if (s.children.size() >= kSelectedBlends) r.d = l.sel(l.lt(l.abs(l.sub(sa, sb)), k), r.d, l.mn(sa, sb));
            r.blend = l.clamp(l.add(l.c(0.5f), l.div(l.mul(l.c(0.5f), l.sub(sa, sb)), kd)), l.c(0), l.c(1));
        }
        if (op != Sides::Union) r.d = l.neg(r.d);
        return r;
    });
}
}  // namespace

Lowered lower_SmoothUnion(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return smooth(l, s, p, inherited, Sides::Union);
}
Bounds bounds_SmoothUnion(const BoundsIn& b) { return joined(b, b.f(SmoothUnionP::k)); }

Lowered lower_SmoothIntersection(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return smooth(l, s, p, inherited, Sides::Intersection);
}
Bounds bounds_SmoothIntersection(const BoundsIn& b) { return met(b); }

Lowered lower_SmoothDifference(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return smooth(l, s, p, inherited, Sides::Difference);
}
Bounds bounds_SmoothDifference(const BoundsIn& b) { return first(b); }

// --- chamfers. hg_sdf's scale the diagonal term by sqrt(1/2); its gradient then reaches
// sqrt(2) where the operands' gradients align. Halving it instead keeps the same surface
// (same sign everywhere) and a 1-Lipschitz field.

Lowered lower_ChamferUnion(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId d = l.mn(l.mn(a, b), l.mul(l.sub(l.add(a, b), P(s, ChamferUnionP::r)), l.c(0.5f)));
        return Step{d, l.lt(a, b)};
    });
}
Bounds bounds_ChamferUnion(const BoundsIn& b) { return joined(b, b.f(ChamferUnionP::r)); }

Lowered lower_ChamferIntersection(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId d = l.mx(l.mx(a, b), l.mul(l.add(l.add(a, b), P(s, ChamferIntersectionP::r)), l.c(0.5f)));
        return Step{d, l.lt(b, a)};
    });
}
Bounds bounds_ChamferIntersection(const BoundsIn& b) { return met(b); }

Lowered lower_ChamferDifference(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId nb = l.neg(b);
        NodeId d = l.mx(l.mx(a, nb), l.mul(l.add(l.add(a, nb), P(s, ChamferDifferenceP::r)), l.c(0.5f)));
        return Step{d, l.lt(nb, a)};
    });
}
Bounds bounds_ChamferDifference(const BoundsIn& b) { return first(b); }

// --- stairs: hg_sdf's fOpUnionStairs; intersection and difference by negation.

namespace {
// r <= 0 is the hard union, as for the smooth and chamfer operations (the steps' width r / n
// would be 0: a modulo by 0, NaN everywhere); a size known only when the program runs
// (time) chooses between the two.
NodeId stairs_union(L& l, NodeId a, NodeId b, NodeId r, NodeId n) {
    const bool known = l.g.is_const(r);
    if (known && !(l.g.const_value(r) > 0.0f)) return l.mn(a, b);
    NodeId s = l.div(r, n);
    NodeId u = l.sub(b, r);
    NodeId m = l.g.binary(Op::Mod, l.add(l.sub(u, a), s), l.mul(l.c(2), s));
    NodeId d = l.mn(l.mn(a, b), l.mul(l.c(0.5f), l.add(l.add(u, a), l.abs(l.sub(m, s)))));
    return known ? d : l.sel(l.lt(l.c(0), r), d, l.mn(a, b));
}
}  // namespace

Lowered lower_StairsUnion(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId d = stairs_union(l, a, b, P(s, StairsUnionP::r), P(s, StairsUnionP::n));
        return Step{d, l.lt(a, b)};
    });
}
Bounds bounds_StairsUnion(const BoundsIn& b) { return joined(b, b.f(StairsUnionP::r)); }

Lowered lower_StairsIntersection(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId d = l.neg(stairs_union(l, l.neg(a), l.neg(b), P(s, StairsIntersectionP::r), P(s, StairsIntersectionP::n)));
        return Step{d, l.lt(b, a)};
    });
}
Bounds bounds_StairsIntersection(const BoundsIn& b) { return met(b); }

Lowered lower_StairsDifference(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return fold(l, s, p, inherited, [&](NodeId a, NodeId b) {
        NodeId d = l.neg(stairs_union(l, l.neg(a), b, P(s, StairsDifferenceP::r), P(s, StairsDifferenceP::n)));
        return Step{d, l.lt(l.neg(b), a)};
    });
}
Bounds bounds_StairsDifference(const BoundsIn& b) { return first(b); }

// --- Choose: both shapes, one distance chosen by a condition on time (constant per frame,
// so the result is as Lipschitz as the two).

Lowered lower_Choose(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Graph& g = l.g;
    Lowered a = lower_shape(g, *s.children.at(0), p, inherited), b = lower_shape(g, *s.children.at(1), p, inherited);
    NodeId c = P(s, ChooseP::cond);
    Lowered out{l.sel(c, unit(g, a), unit(g, b)), 1.0f, {}};
    if (inherited) out.m = select_mat(g, c, a.m, b.m);
    return out;
}
Bounds bounds_Choose(const BoundsIn& b) { return join(b.child(0), b.child(1)); }  // (its condition is never a constant)

}  // namespace sdfc::shapes
