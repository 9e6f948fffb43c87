// The modifiers of shapes.def (LANGUAGE.md section 6): each one moves the point before its
// child is lowered (or changes the child's distance after), with the Lipschitz bound that
// leaves, then its bounding box from the child's. Formulas follow Inigo Quilez and hg_sdf
// (mercury.sexy/hg_sdf) unless a comment says otherwise.
#include <algorithm>
#include <cmath>
#include <optional>

#include "compiler/scene/shape_lowering.hpp"

namespace sdfc::shapes {

namespace {

Lowered child(L& l, const Shape& s, const Vec3N& q, const MaterialN* inherited) {
    return lower_shape(l.g, *s.children.at(0), q, inherited);
}

// A child's bounds with `f` applied, unless they are empty or (with `finite`) unbounded.
template <class F>
Bounds around(const BoundsIn& b, bool finite, F f) {
    Bounds c = b.child();
    if (is_empty(c) || (finite && !c.finite())) return c;
    return f(c);
}

float bound_radius(const Bounds& b) {
    if (!b.finite()) return 10.0f;  // unbounded child: assume the working volume of a scene
    glm::vec3 e = glm::max(glm::abs(b.lo), glm::abs(b.hi));
    return glm::length(e);
}

// Twist and bend multiply the Lipschitz bound by sqrt(1 + (wR)^2) (+ wR for bend), w the
// rate in radians per unit, R the child's radius. Constant w: folded into lip; otherwise
// the distance is divided by the bound as an expression.
Lowered distort_bound(L& l, Lowered r, NodeId w, float R, bool bend) {
    Graph& g = l.g;
    if (g.is_const(w)) {
        float wr = std::fabs(g.const_value(w)) * R;
        r.lip *= std::sqrt(1.0f + wr * wr) + (bend ? wr : 0.0f);
        return r;
    }
    NodeId wr = l.mul(l.abs(w), l.c(R));
    NodeId k = l.sqrt(l.add(l.c(1.0f), l.mul(wr, wr)));
    if (bend) k = l.add(k, wr);
    r.d = l.div(unit(g, r), k);
    r.lip = 1.0f;
    return r;
}

// Bounds of a child turned about the y axis (axis 1: polar_repeat, twist) or the z axis
// (axis 2: bend) by any angle: out to its farthest corner across the axis.
Bounds turned(const Bounds& c, int axis) {
    const int u = 0, v = axis == 1 ? 2 : 1;
    float r = std::sqrt(std::max(c.lo[u] * c.lo[u], c.hi[u] * c.hi[u]) + std::max(c.lo[v] * c.lo[v], c.hi[v] * c.hi[v]));
    Bounds out = c;
    out.lo[u] = out.lo[v] = -r;
    out.hi[u] = out.hi[v] = r;
    return out;
}

// How many neighbouring cells each side a repeat looks into for a child that reaches out of
// its own cell (a larger child is cut beyond that).
constexpr int kRepeatReach = 2;

// polar_repeat(n)'s sectors, centred on its child's direction `centre` (an angle atan2(z, x):
// copy 0 of the child as given), and the copies whose child reaches into sector 0 (angles
// within pi/n of the centre): offsets j, 0 first, at most 2 * kRepeatReach + 1. `floor`:
// the child's angular extent [a0, a1] when it is away from the axis and every copy that
// reaches in was taken, so the copies left out are at least that far round.
struct PolarCopies {
    float centre = 0.0f, a0 = 0.0f, a1 = 0.0f;
    std::vector<int> js{0};
    bool floor = false;
};
PolarCopies polar_neighbours(const Bounds& b, float n) {
    PolarCopies pc;
    if (!(n >= 1.0f) || n != std::floor(n) || !(b.lo.x > -1e29f && b.hi.x < 1e29f && b.lo.z > -1e29f && b.hi.z < 1e29f))
        return pc;
    const float ang = 2.0f * kPi / n;
    const int count = int(std::min(n, 1e6f));
    float a0, a1;  // the child's angular extent
    const bool around = b.lo.x <= 0 && b.hi.x >= 0 && b.lo.z <= 0 && b.hi.z >= 0;
    if (around) {
        a0 = -kPi, a1 = kPi;  // around the axis: every direction
    } else {
        const float ac = std::atan2(0.5f * (b.lo.z + b.hi.z), 0.5f * (b.lo.x + b.hi.x));
        a0 = a1 = 0.0f;
        for (float x : {b.lo.x, b.hi.x})
            for (float z : {b.lo.z, b.hi.z}) {
                float d = std::atan2(z, x) - ac;
                d = d > kPi ? d - 2 * kPi : (d < -kPi ? d + 2 * kPi : d);
                a0 = std::min(a0, d), a1 = std::max(a1, d);
            }
        pc.centre = 0.5f * (a0 + a1) + ac;
        a0 += ac - pc.centre, a1 += ac - pc.centre;  // about the centre
    }
    bool cut = false;
    int jmin = 0, jmax = 0;
    for (int dj = 1; dj <= count / 2; ++dj)
        for (int j : {dj, -dj}) {
            if (j == -dj && 2 * dj == count) continue;  // the same copy as +dj
            bool hit = false;
            for (int k = -2; k <= 2 && !hit; ++k) {
                const float lo = a0 + float(j) * ang + float(k) * 2 * kPi, hi = a1 + float(j) * ang + float(k) * 2 * kPi;
                hit = lo < 0.5f * ang && hi > -0.5f * ang;
            }
            if (!hit) continue;
            if (int(pc.js.size()) >= 2 * kRepeatReach + 1) {
                cut = true;
                continue;
            }
            pc.js.push_back(j);
            jmin = std::min(jmin, j), jmax = std::max(jmax, j);
        }
    // (Those taken are one run jmin..jmax: a copy reaches in only if the ones between do.)
    pc.floor = !around && !cut && count >= 2 && int(pc.js.size()) == jmax - jmin + 1 && int(pc.js.size()) < count;
    pc.a0 = a0 + float(jmin) * ang, pc.a1 = a1 + float(jmax) * ang;  // what the copies taken cover
    // (As for repeat: only where the copies left out keep a twentieth of a sector away.)
    const float taken = ang * float(pc.js.size());
    pc.floor = pc.floor && std::min(pc.a0 + taken - 0.5f * ang, -0.5f * ang - (pc.a1 - taken)) >= 0.05f * ang;
    return pc;
}

// Whether each copy of `s` is the nearest in its own centred cell (or sector), so the
// copies left out need no floor: a sphere (its distance grows with the distance from its
// centre) or, on a lattice, a box along the axes (with each axis' offset), moved by
// translations. Most repeated children in scripts are these.
bool own_copy_nearest(const Shape& s, bool lattice) {
    const Shape* c = &s;
    while ((c->kind == ShapeKind::Translate || c->kind == ShapeKind::Material) && c->children.size() == 1 && c->children[0])
        c = c->children[0].get();
    return c->kind == ShapeKind::Sphere || (lattice && c->kind == ShapeKind::Box);
}

// Domain repetition: the point moves into its cell, and the child is evaluated there. The
// cells are centred on the child's box (an off-centre child, `repeat(v) translate(t) s`,
// sits in the middle of its cell). A child that reaches out of its cell would be cut at the
// cell's faces, so the copies of the neighbouring cells that reach into this one are
// evaluated too (from the child's bounds; none for a child inside its cell, the usual case).
// The copies left out are at least as far as their boxes: that distance is a floor under
// the copies evaluated, so a point near a face never overestimates (a copy next door can be
// nearer than its own). `count`: RepeatFinite's slots.
Lowered repeat(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited, bool finite) {
    static_assert(size_t(RepeatP::period) == size_t(RepeatFiniteP::period));
    Graph& g = l.g;
    // (a count of 1.5 is 1 each side, as in GLSL, where a param count is floored: no copy at 1.5 periods)
    auto count = [&](int i) { return g.unary(Op::Floor, P(s, RepeatFiniteP::count + i)); };
    Vec3N per = P3(s, RepeatP::period);
    Bounds cb = shape_bounds(g, *s.children.at(0));
    // A child that a translate moves by a varying offset (time, a param: GLSL's uniforms)
    // has no constant box, but its box moves with it: the cells are centred on it as it
    // moves (without this GLSL cut the copies at the faces of cells laid out for time 0).
    Vec3N moved{kNoNode, kNoNode, kNoNode};
    if (!cb.finite()) {
        const Shape* c = s.children.at(0).get();
        Vec3N off{l.c(0.0f), l.c(0.0f), l.c(0.0f)};
        bool varies = false;
        for (; (c->kind == ShapeKind::Translate || c->kind == ShapeKind::Material) && c->children.size() == 1 && c->children[0];
             c = c->children[0].get())
            if (c->kind == ShapeKind::Translate) {
                const Vec3N v = P3(*c, TranslateP::v);
                for (int i = 0; i < 3; ++i) varies |= !g.is_const(v[i]), off[i] = l.add(off[i], v[i]);
            }
        const Bounds inner = varies ? shape_bounds(g, *c) : cb;
        if (varies && inner.finite()) cb = inner, moved = off;
    }
    std::array<NodeId, 3> idx{kNoNode, kNoNode, kNoNode};
    std::array<int, 3> jlo{0, 0, 0}, jhi{0, 0, 0};
    std::array<bool, 3> boxed{false, false, false};  // the floor for the copies left out applies
    glm::vec3 mid(0.0f), lo(0.0f), hi(0.0f);          // the child's box about the cells' centres
    Vec3N centre{kNoNode, kNoNode, kNoNode};          // the cells' centre: mid, moved with the child
    for (int i = 0; i < 3; ++i) {
        if (g.is_const(per[i]) && g.const_value(per[i]) == 0.0f) continue;  // axis left alone
        const bool fits = g.is_const(per[i]) && cb.lo[i] > -1e29f && cb.hi[i] < 1e29f && g.const_value(per[i]) > 0.0f;
        if (fits) mid[i] = 0.5f * cb.lo[i] + 0.5f * cb.hi[i], lo[i] = cb.lo[i] - mid[i], hi[i] = cb.hi[i] - mid[i];
        centre[i] = moved[i] != kNoNode && fits ? l.add(moved[i], l.c(mid[i])) : l.c(mid[i]);
        const NodeId at = g.is_const(centre[i]) && g.const_value(centre[i]) == 0.0f ? p[i] : l.sub(p[i], centre[i]);
        idx[i] = g.unary(Op::Floor, l.add(l.div(at, per[i]), l.c(0.5f)));
        if (finite) idx[i] = l.clamp(idx[i], l.neg(count(i)), count(i));
        if (!fits) continue;
        const float pe = g.const_value(per[i]), half = 0.5f * pe;
        // Copy j of the neighbours spans [lo + j pe, hi + j pe]: those overlapping
        // this cell, [-half, half]. At most kRepeatReach each side.
        // (Clamped as floats first: bounds of 1e28 over a period of 0.01 overflow an int.)
        const float lo_j = std::floor((-half - hi[i]) / pe) + 1, hi_j = std::ceil((half - lo[i]) / pe) - 1;
        if (!std::isfinite(lo_j) || !std::isfinite(hi_j)) continue;
        jlo[i] = int(std::clamp(lo_j, float(-kRepeatReach), 0.0f));
        jhi[i] = int(std::clamp(hi_j, 0.0f, float(kRepeatReach)));
        // (Only where the copies left out keep a twentieth of a period from this cell: boxes
        // that fill their cells, a lattice's struts, would floor the distance to 0 on every
        // face. Such a child is its cell's nearest copy when it is symmetric, as they are.)
        const float gap = std::min(lo[i] + float(jhi[i] + 1) * pe - half, -half - hi[i] - float(jlo[i] - 1) * pe);
        boxed[i] = std::isfinite(gap) && gap >= 0.05f * pe && !own_copy_nearest(*s.children.at(0), true);
    }
    std::optional<Lowered> acc;  // the copies are one child: one Lipschitz bound
    for (int jx = jlo[0]; jx <= jhi[0]; ++jx)
        for (int jy = jlo[1]; jy <= jhi[1]; ++jy)
            for (int jz = jlo[2]; jz <= jhi[2]; ++jz) {
                const int j[3] = {jx, jy, jz};
                Vec3N q = p;
                for (int i = 0; i < 3; ++i) {
                    if (idx[i] == kNoNode) continue;
                    NodeId c = idx[i];
                    if (j[i] != 0) {
                        c = l.add(c, l.c(float(j[i])));
                        if (finite) c = l.clamp(c, l.neg(count(i)), count(i));
                    }
                    q[i] = l.sub(p[i], l.mul(per[i], c));
                }
                Lowered r = child(l, s, q, inherited);
                acc = acc ? nearer(l, *acc, r, inherited) : r;
            }
    // The floor: along a boxed axis, the copies past the last one evaluated each side (those
    // that exist: a finite repeat has none past its ends), no nearer than their boxes; along
    // the other axes no nearer than the child's box (in its own cell where repeated: the
    // nearest box there when the child fits it).
    std::array<NodeId, 3> u{kNoNode, kNoNode, kNoNode}, gap{kNoNode, kNoNode, kNoNode};
    for (int i = 0; i < 3; ++i) {
        const bool own = boxed[i] && jlo[i] == 0 && jhi[i] == 0;
        if (boxed[i]) u[i] = l.sub(l.sub(p[i], centre[i]), l.mul(per[i], idx[i]));  // in [-half, half] but past a finite end
        if (own) gap[i] = l.mx(l.mx(l.sub(l.c(lo[i]), u[i]), l.sub(u[i], l.c(hi[i]))), l.c(0.0f));
        else if (idx[i] == kNoNode && moved[i] == kNoNode && cb.lo[i] > -1e29f && cb.hi[i] < 1e29f)
            gap[i] = l.mx(l.mx(l.sub(l.c(cb.lo[i]), p[i]), l.sub(p[i], l.c(cb.hi[i]))), l.c(0.0f));
    }
    NodeId floor = kNoNode;
    for (int i = 0; i < 3; ++i) {
        if (!boxed[i]) continue;
        const float pe = g.const_value(per[i]);
        NodeId above = l.sub(l.c(lo[i] + float(jhi[i] + 1) * pe), u[i]), below = l.sub(u[i], l.c(hi[i] + float(jlo[i] - 1) * pe));
        if (finite) {
            above = l.sel(l.lt(l.add(idx[i], l.c(float(jhi[i]))), count(i)), above, l.c(1e30f));
            below = l.sel(l.lt(l.neg(count(i)), l.add(idx[i], l.c(float(jlo[i])))), below, l.c(1e30f));
        }
        const int k1 = (i + 1) % 3, k2 = (i + 2) % 3;
        const NodeId side = l.len3(l.mn(above, below), gap[k1] == kNoNode ? l.c(0.0f) : gap[k1], gap[k2] == kNoNode ? l.c(0.0f) : gap[k2]);
        floor = floor == kNoNode ? side : l.mn(floor, side);
    }
    if (floor != kNoNode) acc->d = l.mn(acc->d, floor);
    return *acc;
}

}  // namespace

Lowered lower_Translate(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return child(l, s, l.sub3(p, P3(s, TranslateP::v)), inherited);
}
Bounds bounds_Translate(const BoundsIn& b) {
    return around(b, false, [&](const Bounds& c) { return Bounds{c.lo + b.v3(TranslateP::v), c.hi + b.v3(TranslateP::v)}; });
}

namespace {
// The box around a child's box mapped by m (column-major, glm's).
Bounds mapped(const BoundsIn& b, const glm::mat3& m) {
    Bounds c = b.child();
    if (is_empty(c) || !c.finite()) return is_empty(c) ? c : infinite();
    return mapped_box(c, m);
}
}  // namespace

Lowered lower_Rotate(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    // The shape turns by R, so the point turns back by R^T.
    const NodeId* m = &s.params.at(RotateP::m);
    Vec3N q;
    for (int i = 0; i < 3; ++i) q[i] = l.add(l.add(l.mul(m[i], p[0]), l.mul(m[3 + i], p[1])), l.mul(m[6 + i], p[2]));
    return child(l, s, q, inherited);
}
Bounds bounds_Rotate(const BoundsIn& b) {
    return mapped(b, rotation_rows([&](size_t k) { return b.v.at(RotateP::m + k); }));
}

Lowered lower_Scale(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Vec3N sc = P3(s, ScaleP::s);
    Lowered r = child(l, s, {l.div(p[0], sc[0]), l.div(p[1], sc[1]), l.div(p[2], sc[2])}, inherited);
    // d(p/s)*min(s) is a bound for any scale; exact when uniform.
    r.d = l.mul(r.d, l.mn(sc[0], l.mn(sc[1], sc[2])));
    return r;
}
Bounds bounds_Scale(const BoundsIn& b) {
    return around(b, true, [&](const Bounds& c) { return Bounds{c.lo * b.v3(ScaleP::s), c.hi * b.v3(ScaleP::s)}; });
}

Lowered lower_Mirror(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Vec3N n = P3(s, MirrorP::normal);  // unit (lang/builtins.cpp divides by its length)
    NodeId k = l.mul(l.c(2), l.dot3(p, n));
    return child(l, s, {l.sub(p[0], l.mul(k, n[0])), l.sub(p[1], l.mul(k, n[1])), l.sub(p[2], l.mul(k, n[2]))}, inherited);
}
Bounds bounds_Mirror(const BoundsIn& b) {
    glm::vec3 n = b.v3(MirrorP::normal);
    return mapped(b, glm::mat3(1.0f) - 2.0f * glm::outerProduct(n, n));
}

Lowered lower_Repeat(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return repeat(l, s, p, inherited, false);
}
Bounds bounds_Repeat(const BoundsIn& b) {
    Bounds c = b.child();
    for (int i = 0; i < 3; ++i)
        if (b.v[RepeatP::period + i] != 0.0f) { c.lo[i] = -kInf; c.hi[i] = kInf; }
    return c;
}

Lowered lower_RepeatFinite(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    return repeat(l, s, p, inherited, true);
}
Bounds bounds_RepeatFinite(const BoundsIn& b) {
    return around(b, false, [&](Bounds c) {
        for (int i = 0; i < 3; ++i) {
            float e = std::fabs(b.v[RepeatFiniteP::period + i]) * std::fabs(b.v[RepeatFiniteP::count + i]);
            if (c.lo[i] > -kInf * 0.1f) c.lo[i] -= e;
            if (c.hi[i] < kInf * 0.1f) c.hi[i] += e;
        }
        return c;
    });
}

Lowered lower_PolarRepeat(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    // hg_sdf pModPolar around y, its sectors centred on the child's direction (copy 0 as
    // given). As for repeat, the copies of the neighbouring sectors that reach into this one
    // are evaluated too, and those left out are a floor: a point at radius r, an angle d from
    // their sectors, is at least r sin(min(d, pi / 2)) away.
    Graph& g = l.g;
    // A count is whole, the part after the point dropped (a param's slider, -D n=2.5), as
    // repeat's: the same on the CPU and in the shader.
    NodeId n = l.mx(g.unary(Op::Floor, P(s, PolarRepeatP::n)), l.c(1.0f));
    NodeId ang = l.div(l.c(2 * kPi), n);
    const Bounds cb = shape_bounds(g, *s.children.at(0));
    PolarCopies pc;
    if (g.is_const(n)) pc = polar_neighbours(cb, g.const_value(n));
    const NodeId centre = l.c(pc.centre);
    NodeId a = l.add(l.sub(g.binary(Op::Atan2, p[2], p[0]), centre), l.mul(ang, l.c(0.5f)));
    NodeId r = l.len2(p[0], p[2]);
    a = l.sub(g.binary(Op::Mod, a, ang), l.mul(ang, l.c(0.5f)));  // about the centre
    std::optional<Lowered> acc;
    for (int j : pc.js) {
        NodeId aj = l.add(j == 0 ? a : l.sub(a, l.mul(ang, l.c(float(j)))), centre);
        Lowered c = child(l, s, {l.mul(g.unary(Op::Cos, aj), r), p[1], l.mul(g.unary(Op::Sin, aj), r)}, inherited);
        acc = acc ? nearer(l, *acc, c, inherited) : c;
    }
    if (pc.floor && !own_copy_nearest(*s.children.at(0), false)) {
        const float step = 2 * kPi / g.const_value(n);
        // Round from a to the next copy left out either way, at most a quarter turn.
        const NodeId above = l.sub(l.c(pc.a0 + step * float(pc.js.size())), a), below = l.sub(a, l.c(pc.a1 - step * float(pc.js.size())));
        const NodeId d = l.clamp(l.mn(above, below), l.c(0.0f), l.c(0.5f * kPi));
        // (no nearer than its height either)
        const NodeId dy = cb.lo.y > -1e29f && cb.hi.y < 1e29f
                              ? l.mx(l.mx(l.sub(l.c(cb.lo.y), p[1]), l.sub(p[1], l.c(cb.hi.y))), l.c(0.0f))
                              : l.c(0.0f);
        // (nor nearer than the copies' ring: every copy lies at least rmin from the axis, so
        // a point near the axis, where r sin(d) is 0, is not taken for a surface)
        const float rmin = std::hypot(std::max({cb.lo.x, -cb.hi.x, 0.0f}), std::max({cb.lo.z, -cb.hi.z, 0.0f}));
        const NodeId across = rmin > 0.0f ? l.mx(l.mul(r, g.unary(Op::Sin, d)), l.sub(l.c(rmin), r)) : l.mul(r, g.unary(Op::Sin, d));
        acc->d = l.mn(acc->d, l.len2(across, dy));
    }
    return *acc;
}
Bounds bounds_PolarRepeat(const BoundsIn& b) {
    return around(b, true, [](const Bounds& c) { return turned(c, 1); });
}

Lowered lower_Symmetry(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Graph& g = l.g;
    Vec3N q = p;
    for (int i = 0; i < 3; ++i) {
        const NodeId fold = P(s, SymmetryP::x + i);
        if (!(g.is_const(fold) && g.const_value(fold) == 0.0f)) q[i] = l.sel(fold, l.abs(p[i]), p[i]);
    }
    return child(l, s, q, inherited);
}
Bounds bounds_Symmetry(const BoundsIn& b) {
    return around(b, false, [&](Bounds c) {
        for (int i = 0; i < 3; ++i)
            if (b.v[SymmetryP::x + i] != 0.0f) {
                float e = std::max(std::fabs(c.lo[i]), std::fabs(c.hi[i]));
                c.lo[i] = -e;
                c.hi[i] = e;
            }
        return c;
    });
}

Lowered lower_Elongate(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    // Quilez's elongation, basic form: q = p - clamp(p, -h, h), h = v / 2.
    Vec3N h = P3(s, ElongateP::v);
    Vec3N q;
    for (int i = 0; i < 3; ++i) {
        NodeId hh = l.mul(h[i], l.c(0.5f));
        q[i] = l.sub(p[i], l.clamp(p[i], l.neg(hh), hh));
    }
    return child(l, s, q, inherited);
}
Bounds bounds_Elongate(const BoundsIn& b) {
    return around(b, false, [&](const Bounds& c) {
        glm::vec3 h = glm::abs(b.v3(ElongateP::v)) * 0.5f;
        return Bounds{c.lo - h, c.hi + h};
    });
}

Lowered lower_Twist(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Graph& g = l.g;
    NodeId w = l.mul(P(s, TwistP::rate), l.c(kDeg));
    NodeId a = l.mul(w, p[1]);
    NodeId cs = g.unary(Op::Cos, a), sn = g.unary(Op::Sin, a);
    Lowered r = child(l, s, {l.sub(l.mul(cs, p[0]), l.mul(sn, p[2])), p[1], l.add(l.mul(sn, p[0]), l.mul(cs, p[2]))}, inherited);
    // |J| <= sqrt(1 + (w R)^2) with R the child's radius about the axis. A rate that
    // depends on time (GLSL) divides by the same bound computed at run time.
    return distort_bound(l, r, w, bound_radius(shape_bounds(g, *s.children[0])), false);
}
Bounds bounds_Twist(const BoundsIn& b) {
    return around(b, true, [](const Bounds& c) { return turned(c, 1); });
}

Lowered lower_Bend(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Graph& g = l.g;
    NodeId w = l.mul(P(s, BendP::rate), l.c(kDeg));
    NodeId a = l.mul(w, p[0]);
    NodeId cs = g.unary(Op::Cos, a), sn = g.unary(Op::Sin, a);
    Lowered r = child(l, s, {l.sub(l.mul(cs, p[0]), l.mul(sn, p[1])), l.add(l.mul(sn, p[0]), l.mul(cs, p[1])), p[2]}, inherited);
    return distort_bound(l, r, w, bound_radius(shape_bounds(g, *s.children[0])), true);
}
Bounds bounds_Bend(const BoundsIn& b) {
    return around(b, true, [](const Bounds& c) { return turned(c, 2); });
}

Lowered lower_Round(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Lowered r = child(l, s, p, inherited);
    r.d = l.sub(unit(l.g, r), P(s, RoundP::r));
    r.lip = 1.0f;
    return r;
}
Bounds bounds_Round(const BoundsIn& b) { return grow(b.child(), b.f(RoundP::r)); }

Lowered lower_Onion(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Lowered r = child(l, s, p, inherited);
    r.d = l.sub(l.abs(unit(l.g, r)), P(s, OnionP::thickness));
    r.lip = 1.0f;
    return r;
}
Bounds bounds_Onion(const BoundsIn& b) { return grow(b.child(), b.f(OnionP::thickness)); }

// The child's cross-section at z = 0, d2, extruded: max-combined exactly with |z| - h/2
// (the 2D box formula of (d2, |z| - h/2)).
Lowered lower_Extrude(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Lowered r = child(l, s, {p[0], p[1], l.c(0.0f)}, inherited);
    const NodeId d2 = unit(l.g, r);
    r.d = l.box2_q(d2, l.sub(l.abs(p[2]), l.mul(P(s, ExtrudeP::h), l.c(0.5f))));
    r.lip = 1.0f;
    return r;
}
Bounds bounds_Extrude(const BoundsIn& b) {
    Bounds c = b.child();
    if (is_empty(c)) return c;
    const float h = 0.5f * b.f(ExtrudeP::h);
    c.lo.z = -h, c.hi.z = h;
    return c;
}

// Quilez's revolution: the child's cross-section at z = 0 at (length(p.xz) - offset, p.y).
Lowered lower_Revolve(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Lowered r = child(l, s, {l.sub(l.len2(p[0], p[2]), P(s, RevolveP::offset)), p[1], l.c(0.0f)}, inherited);
    return r;  // a 1-Lipschitz map of p: the child's bound holds
}
Bounds bounds_Revolve(const BoundsIn& b) {
    const Bounds c = b.child();
    if (is_empty(c)) return c;
    const float o = b.v.at(RevolveP::offset);
    if (!(c.lo.x > -kInf * 0.1f && c.hi.x < kInf * 0.1f)) return Bounds{{-kInf, c.lo.y, -kInf}, {kInf, c.hi.y, kInf}};
    const float R = std::max(std::fabs(c.lo.x + o), std::fabs(c.hi.x + o));
    return Bounds{{-R, c.lo.y, -R}, {R, c.hi.y, R}};
}

Lowered lower_Displace(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Graph& g = l.g;
    Lowered r = child(l, s, p, inherited);
    NodeId amt = P(s, DisplaceP::amount), f = P(s, DisplaceP::frequency);
    NodeId n = g.ternary(Op::Noise3, l.mul(p[0], f), l.mul(p[1], f), l.mul(p[2], f));
    r.d = l.add(unit(g, r), l.mul(amt, n));
    float a = g.is_const(amt) ? std::fabs(g.const_value(amt)) : 1.0f;
    float fr = g.is_const(f) ? std::fabs(g.const_value(f)) : 1.0f;
    r.lip = 1.0f + a * fr * om::kNoiseLipschitz;
    return r;
}
Bounds bounds_Displace(const BoundsIn& b) { return grow(b.child(), b.f(DisplaceP::amount) * 1.5f); }

Lowered lower_Material(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    // The inner material wins: this one only reaches shapes that have none of their own,
    // so it replaces what the enclosing scope passed down.
    if (inherited && s.color_at) {  // a colour field: its colour at this point
        MaterialN m = s.material;
        const Vec3N c = s.color_at(l.g, p);
        for (int k = 0; k < 3; ++k) m[size_t(kMatR + k)] = c[size_t(k)];
        return child(l, s, p, &m);
    }
    return child(l, s, p, inherited ? &s.material : nullptr);
}
Bounds bounds_Material(const BoundsIn& b) { return b.child(); }

}  // namespace sdfc::shapes
