// Shape tree -> IR. Formulas follow Inigo Quilez's distance-function list (iquilezles.org,
// "distfunctions") and hg_sdf (mercury.sexy/hg_sdf) unless a comment says otherwise.
// Every case returns a distance and its Lipschitz bound; combinators divide children by
// their bound first, so one distorting modifier does not make the whole scene conservative.
#include "compiler/scene/lower.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <numbers>

namespace sdfc {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kDeg = kPi / 180.0f;

struct L {  // lowering context: graph + helpers on 3-vectors of nodes
    Graph& g;
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

NodeId P(const Shape& s, size_t i) { return s.params.at(i); }
Vec3N P3(const Shape& s, size_t i) { return {s.params.at(i), s.params.at(i + 1), s.params.at(i + 2)}; }

bool is_csg(ShapeKind k) { return k >= ShapeKind::Union && k <= ShapeKind::StairsDifference; }

// Normalised child distance (1-Lipschitz).
NodeId unit(Graph& g, const Lowered& l) { return l.lip == 1.0f ? l.d : g.mulc(l.d, 1.0f / l.lip); }

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

// The nearer of two lowered shapes with the same Lipschitz bound (a's on ties), with its
// material when materials are lowered.
Lowered nearer(L& l, const Lowered& a, const Lowered& b, bool materials) {
    Lowered r{l.mn(a.d, b.d), a.lip, {}};
    if (materials) r.m = select_mat(l.g, l.lt(a.d, b.d), a.m, b.m);
    return r;
}

float bound_radius(const Bounds& b) {
    if (!b.finite()) return 10.0f;  // unbounded child: assume the working volume of a scene
    glm::vec3 e = glm::max(glm::abs(b.lo), glm::abs(b.hi));
    return glm::length(e);
}

Lowered lower_primitive(L& l, const Shape& s, const Vec3N& p);

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
Lowered lower_csg(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited);

}  // namespace

namespace {

// How many neighbouring cells each side a repeat looks into for a child that reaches out of
// its own cell (a larger child is cut beyond that).
constexpr int kRepeatReach = 2;

// The copies of polar_repeat(n) whose child (bounds `b`, copy 0 as given) reaches into
// sector 0, the one centred on +x (angles atan2(z, x) in [-pi/n, pi/n]): offsets j such
// that the child turned by j sectors overlaps it. 0 first; at most 2 * kRepeatReach + 1.
std::vector<int> polar_neighbours(const Bounds& b, float n) {
    std::vector<int> js{0};
    if (!(n >= 1.0f) || n != std::floor(n) || !(b.lo.x > -1e29f && b.hi.x < 1e29f && b.lo.z > -1e29f && b.hi.z < 1e29f))
        return js;
    const float ang = 2.0f * kPi / n;
    const int count = int(std::min(n, 1e6f));
    float a0, a1;  // the child's angular extent
    if (b.lo.x <= 0 && b.hi.x >= 0 && b.lo.z <= 0 && b.hi.z >= 0) {
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
        a0 += ac, a1 += ac;
    }
    for (int dj = 1; dj <= count / 2 && int(js.size()) < 2 * kRepeatReach + 1; ++dj)
        for (int j : {dj, -dj}) {
            if (j == -dj && 2 * dj == count) continue;  // the same copy as +dj
            bool hit = false;
            for (int k = -2; k <= 2 && !hit; ++k) {
                const float lo = a0 + float(j) * ang + float(k) * 2 * kPi, hi = a1 + float(j) * ang + float(k) * 2 * kPi;
                hit = lo < 0.5f * ang && hi > -0.5f * ang;
            }
            if (hit && int(js.size()) < 2 * kRepeatReach + 1) js.push_back(j);
        }
    return js;
}

}  // namespace

NodeId lower_distance(Graph& g, const Shape& shape, const Vec3N& p) {
    Lowered r = lower_shape(g, shape, p, nullptr);
    return unit(g, r);
}

Lowered lower_shape(Graph& g, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    check_stack(s.loc);
    Loc saved = g.loc();
    if (s.loc.known()) g.set_loc(s.loc);
    L l{g};
    Lowered out;
    auto child = [&](const Vec3N& q, const MaterialN* m = nullptr) {
        return lower_shape(g, *s.children.at(0), q, m ? m : inherited);
    };
    switch (s.kind) {
        case ShapeKind::Translate:
            out = child(l.sub3(p, P3(s, 0)));
            break;
        case ShapeKind::Rotate: {
            // The shape turns by R, so the point turns back by R^T.
            const auto& m = s.params;
            Vec3N q;
            for (int i = 0; i < 3; ++i)
                q[i] = l.add(l.add(l.mul(m[i], p[0]), l.mul(m[3 + i], p[1])), l.mul(m[6 + i], p[2]));
            out = child(q);
            break;
        }
        case ShapeKind::Scale: {
            Vec3N sc = P3(s, 0);
            Lowered r = child({l.div(p[0], sc[0]), l.div(p[1], sc[1]), l.div(p[2], sc[2])});
            // d(p/s)*min(s) is a bound for any scale; exact when uniform.
            r.d = l.mul(r.d, l.mn(sc[0], l.mn(sc[1], sc[2])));
            out = r;
            break;
        }
        case ShapeKind::Mirror: {
            Vec3N n = P3(s, 0);
            NodeId k = l.mul(l.c(2), l.dot3(p, n));
            out = child({l.sub(p[0], l.mul(k, n[0])), l.sub(p[1], l.mul(k, n[1])), l.sub(p[2], l.mul(k, n[2]))});
            break;
        }
        case ShapeKind::Repeat:
        case ShapeKind::RepeatFinite: {
            // Domain repetition: the point moves into the cell of the nearest copy. A child
            // that reaches out of its cell would be cut at the cell's faces, so the copies of
            // the neighbouring cells that reach into this one are evaluated too (from the
            // child's bounds; none for a child inside its cell, the usual case).
            Vec3N per = P3(s, 0);
            const Bounds cb = shape_bounds(g, *s.children.at(0));
            std::array<NodeId, 3> idx{kNoNode, kNoNode, kNoNode};
            std::array<int, 3> jlo{0, 0, 0}, jhi{0, 0, 0};
            for (int i = 0; i < 3; ++i) {
                if (g.is_const(per[i]) && g.const_value(per[i]) == 0.0f) continue;  // axis left alone
                idx[i] = g.unary(Op::Floor, l.add(l.div(p[i], per[i]), l.c(0.5f)));
                if (s.kind == ShapeKind::RepeatFinite) idx[i] = l.clamp(idx[i], l.neg(P(s, 3 + i)), P(s, 3 + i));
                if (!g.is_const(per[i]) || !(cb.lo[i] > -1e29f && cb.hi[i] < 1e29f)) continue;
                const float pe = g.const_value(per[i]), half = 0.5f * pe;  // > 0 (checked by repeat)
                // Copy j of the neighbours spans [lo + j pe, hi + j pe]: those overlapping
                // this cell, [-half, half]. At most kRepeatReach each side.
                // (Clamped as floats first: bounds of 1e28 over a period of 0.01 overflow an int.)
                const float lo_j = std::floor((-half - cb.hi[i]) / pe) + 1, hi_j = std::ceil((half - cb.lo[i]) / pe) - 1;
                if (!(pe > 0) || !std::isfinite(lo_j) || !std::isfinite(hi_j)) continue;
                jlo[i] = int(std::clamp(lo_j, float(-kRepeatReach), 0.0f));
                jhi[i] = int(std::clamp(hi_j, 0.0f, float(kRepeatReach)));
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
                                if (s.kind == ShapeKind::RepeatFinite) c = l.clamp(c, l.neg(P(s, 3 + i)), P(s, 3 + i));
                            }
                            q[i] = l.sub(p[i], l.mul(per[i], c));
                        }
                        Lowered r = child(q);
                        acc = acc ? nearer(l, *acc, r, inherited) : r;
                    }
            out = *acc;
            break;
        }
        case ShapeKind::PolarRepeat: {
            // hg_sdf pModPolar around y; copy 0 points along +x. As for repeat, the copies of
            // the neighbouring sectors that reach into this one are evaluated too.
            NodeId n = P(s, 0);
            NodeId ang = l.div(l.c(2 * kPi), n);
            NodeId a = l.add(g.binary(Op::Atan2, p[2], p[0]), l.mul(ang, l.c(0.5f)));
            NodeId r = l.len2(p[0], p[2]);
            a = l.sub(g.binary(Op::Mod, a, ang), l.mul(ang, l.c(0.5f)));
            std::vector<int> js{0};
            if (g.is_const(n)) js = polar_neighbours(shape_bounds(g, *s.children.at(0)), g.const_value(n));
            std::optional<Lowered> acc;
            for (int j : js) {
                NodeId aj = j == 0 ? a : l.sub(a, l.mul(ang, l.c(float(j))));
                Lowered c = child({l.mul(g.unary(Op::Cos, aj), r), p[1], l.mul(g.unary(Op::Sin, aj), r)});
                acc = acc ? nearer(l, *acc, c, inherited) : c;
            }
            out = *acc;
            break;
        }
        case ShapeKind::Choose: {
            // Both shapes, one distance chosen by a condition on time (constant per frame,
            // so the result is as Lipschitz as the two).
            Lowered a = lower_shape(g, *s.children.at(0), p, inherited), b = lower_shape(g, *s.children.at(1), p, inherited);
            NodeId c = P(s, 0);
            out = Lowered{l.sel(c, unit(g, a), unit(g, b)), 1.0f, {}};
            if (inherited) out.m = select_mat(g, c, a.m, b.m);
            break;
        }
        case ShapeKind::Symmetry: {
            Vec3N q = p;
            for (int i = 0; i < 3; ++i)
                if (!(g.is_const(P(s, i)) && g.const_value(P(s, i)) == 0.0f))
                    q[i] = l.sel(P(s, i), l.abs(p[i]), p[i]);
            out = child(q);
            break;
        }
        case ShapeKind::Elongate: {
            // Quilez's elongation, basic form: q = p - clamp(p, -h, h), h = v / 2.
            Vec3N h = P3(s, 0);
            Vec3N q;
            for (int i = 0; i < 3; ++i) {
                NodeId hh = l.mul(h[i], l.c(0.5f));
                q[i] = l.sub(p[i], l.clamp(p[i], l.neg(hh), hh));
            }
            out = child(q);
            break;
        }
        case ShapeKind::Twist: {
            NodeId w = l.mul(P(s, 0), l.c(kDeg));
            NodeId a = l.mul(w, p[1]);
            NodeId cs = g.unary(Op::Cos, a), sn = g.unary(Op::Sin, a);
            Lowered r = child({l.sub(l.mul(cs, p[0]), l.mul(sn, p[2])), p[1], l.add(l.mul(sn, p[0]), l.mul(cs, p[2]))});
            // |J| <= sqrt(1 + (w R)^2) with R the child's radius about the axis. A rate that
            // depends on time (GLSL) divides by the same bound computed at run time.
            out = distort_bound(l, r, w, bound_radius(shape_bounds(g, *s.children[0])), false);
            break;
        }
        case ShapeKind::Bend: {
            NodeId w = l.mul(P(s, 0), l.c(kDeg));
            NodeId a = l.mul(w, p[0]);
            NodeId cs = g.unary(Op::Cos, a), sn = g.unary(Op::Sin, a);
            Lowered r = child({l.sub(l.mul(cs, p[0]), l.mul(sn, p[1])), l.add(l.mul(sn, p[0]), l.mul(cs, p[1])), p[2]});
            out = distort_bound(l, r, w, bound_radius(shape_bounds(g, *s.children[0])), true);
            break;
        }
        case ShapeKind::Round: {
            Lowered r = child(p);
            r.d = l.sub(unit(g, r), P(s, 0));
            r.lip = 1.0f;
            out = r;
            break;
        }
        case ShapeKind::Onion: {
            Lowered r = child(p);
            r.d = l.sub(l.abs(unit(g, r)), P(s, 0));
            r.lip = 1.0f;
            out = r;
            break;
        }
        case ShapeKind::Displace: {
            Lowered r = child(p);
            NodeId amt = P(s, 0), f = P(s, 1);
            NodeId n = g.ternary(Op::Noise3, l.mul(p[0], f), l.mul(p[1], f), l.mul(p[2], f));
            r.d = l.add(unit(g, r), l.mul(amt, n));
            float a = g.is_const(amt) ? std::fabs(g.const_value(amt)) : 1.0f;
            float fr = g.is_const(f) ? std::fabs(g.const_value(f)) : 1.0f;
            r.lip = 1.0f + a * fr * om::kNoiseLipschitz;
            out = r;
            break;
        }
        case ShapeKind::Material:
            // The inner material wins: this one only reaches shapes that have none of their own,
            // so it replaces what the enclosing scope passed down.
            out = lower_shape(g, *s.children.at(0), p, inherited ? &s.material : nullptr);
            break;
        default:
            if (is_csg(s.kind)) {
                out = lower_csg(l, s, p, inherited);
            } else {
                out = lower_primitive(l, s, p);
                if (inherited) out.m = *inherited;
            }
            break;
    }
    g.set_loc(saved);
    return out;
}

namespace {

Lowered lower_primitive(L& l, const Shape& s, const Vec3N& p) {
    Graph& g = l.g;
    NodeId x = p[0], y = p[1], z = p[2];
    NodeId half = l.c(0.5f), zero = l.c(0);
    float lip = 1.0f;
    NodeId d = kNoNode;
    switch (s.kind) {
        case ShapeKind::Empty:
            d = l.c(1e20f);
            break;
        case ShapeKind::Sphere:
            d = l.sub(l.len3(x, y, z), P(s, 0));
            break;
        case ShapeKind::Box: {
            Vec3N b = P3(s, 0), a = l.abs3(p);
            d = l.box_q({l.sub(a[0], l.mul(b[0], half)), l.sub(a[1], l.mul(b[1], half)), l.sub(a[2], l.mul(b[2], half))});
            break;
        }
        case ShapeKind::RoundBox: {
            Vec3N b = P3(s, 0), a = l.abs3(p);
            NodeId r = P(s, 3);
            Vec3N q;
            for (int i = 0; i < 3; ++i) q[i] = l.add(l.sub(a[i], l.mul(b[i], half)), r);
            d = l.sub(l.box_q(q), r);
            break;
        }
        case ShapeKind::BoxFrame: {
            // Quilez's sdBoxFrame makes bars 2e thick; ours are `e` thick.
            Vec3N b = P3(s, 0), a = l.abs3(p);
            NodeId e = l.mul(P(s, 3), half);
            Vec3N pp, q;
            for (int i = 0; i < 3; ++i) {
                pp[i] = l.sub(a[i], l.mul(b[i], half));
                q[i] = l.sub(l.abs(l.add(pp[i], e)), e);
            }
            d = l.mn(l.mn(l.box_q({pp[0], q[1], q[2]}), l.box_q({q[0], pp[1], q[2]})), l.box_q({q[0], q[1], pp[2]}));
            break;
        }
        case ShapeKind::Torus:
            d = l.sub(l.len2(l.sub(l.len2(x, z), P(s, 0)), y), P(s, 1));
            break;
        case ShapeKind::CappedTorus: {
            // Quilez's sdCappedTorus with the ring in the xz-plane (like torus) and the arc of
            // `angle` degrees symmetric about +z: his (x, y, z) are our (|x|, z, y).
            // The angle is clamped to [0, 360] (a time-dependent one can leave it), and sin of
            // the half angle to >= 0: sin(180 deg) in floats is -8.7e-8, which made the branch
            // test flip on the plane x = 0 of a full (360 degree) ring.
            NodeId an = l.mul(l.clamp(P(s, 0), zero, l.c(360.0f)), l.c(0.5f * kDeg));
            NodeId sx = l.mx(g.unary(Op::Sin, an), zero), sy = g.unary(Op::Cos, an);
            NodeId qx = l.abs(x), qy = z;
            NodeId ra = P(s, 1), rb = P(s, 2);
            NodeId k = l.sel(l.lt(l.mul(sx, qy), l.mul(sy, qx)), l.add(l.mul(qx, sx), l.mul(qy, sy)), l.len2(qx, qy));
            NodeId dd = l.add(l.add(l.add(l.sq(qx), l.sq(qy)), l.sq(y)), l.sub(l.sq(ra), l.mul(l.mul(l.c(2), ra), k)));
            d = l.sub(l.sqrt(l.mx(dd, zero)), rb);
            break;
        }
        case ShapeKind::Link: {
            // Quilez's sdLink: straight sections along y of total length `length`, ring in xy.
            NodeId le = l.mul(P(s, 0), half);
            NodeId qy = l.mx(l.sub(l.abs(y), le), zero);
            d = l.sub(l.len2(l.sub(l.len2(x, qy), P(s, 1)), z), P(s, 2));
            break;
        }
        case ShapeKind::Cylinder: {
            NodeId dx = l.sub(l.len2(x, z), P(s, 1));
            NodeId dy = l.sub(l.abs(y), l.mul(P(s, 0), half));
            d = l.box2_q(dx, dy);
            break;
        }
        case ShapeKind::RoundCylinder: {
            NodeId e = P(s, 2);
            NodeId dx = l.add(l.sub(l.len2(x, z), P(s, 1)), e);
            NodeId dy = l.add(l.sub(l.abs(y), l.mul(P(s, 0), half)), e);
            d = l.sub(l.box2_q(dx, dy), e);
            break;
        }
        case ShapeKind::Capsule: {
            Vec3N a = P3(s, 0), b = P3(s, 3);
            Vec3N pa = l.sub3(p, a), ba = l.sub3(b, a);
            NodeId bb = l.dot3(ba, ba);
            NodeId h = (g.is_const(bb) && g.const_value(bb) == 0.0f) ? zero : l.clamp(l.div(l.dot3(pa, ba), bb), zero, l.c(1));
            d = l.sub(l.len3(l.sub(pa[0], l.mul(ba[0], h)), l.sub(pa[1], l.mul(ba[1], h)), l.sub(pa[2], l.mul(ba[2], h))),
                      P(s, 6));
            break;
        }
        case ShapeKind::Cone: {
            // Quilez's sdCappedCone (exact): base radius r1 at y = -h/2, top radius r2 at +h/2.
            NodeId h = l.mul(P(s, 0), half), r1 = P(s, 1), r2 = P(s, 2);
            NodeId qx = l.len2(x, z), qy = y;
            NodeId k1x = r2, k1y = h, k2x = l.sub(r2, r1), k2y = l.mul(l.c(2), h);
            NodeId cax = l.sub(qx, l.mn(qx, l.sel(l.lt(qy, zero), r1, r2)));
            NodeId cay = l.sub(l.abs(qy), h);
            NodeId k2k2 = l.add(l.sq(k2x), l.sq(k2y));
            NodeId t = l.clamp(l.div(l.add(l.mul(l.sub(k1x, qx), k2x), l.mul(l.sub(k1y, qy), k2y)), k2k2), zero, l.c(1));
            NodeId cbx = l.add(l.sub(qx, k1x), l.mul(k2x, t));
            NodeId cby = l.add(l.sub(qy, k1y), l.mul(k2y, t));
            NodeId sgn = l.sel(g.binary(Op::And, l.lt(cbx, zero), l.lt(cay, zero)), l.c(-1), l.c(1));
            d = l.mul(sgn, l.sqrt(l.mn(l.add(l.sq(cax), l.sq(cay)), l.add(l.sq(cbx), l.sq(cby)))));
            break;
        }
        case ShapeKind::Plane: {
            Vec3N n = P3(s, 0);
            NodeId len = l.len3(n[0], n[1], n[2]);
            d = l.sub(l.div(l.dot3(p, n), len), P(s, 3));
            break;
        }
        case ShapeKind::Ellipsoid: {
            // (length(p / r) - 1) * min(r): 1-Lipschitz, exact along the shortest axis, a bound
            // elsewhere. (Quilez's k0 (k0 - 1) / k1 is tighter near the surface but its gradient
            // reaches several times 1 near the centre of elongated ellipsoids.)
            Vec3N r = P3(s, 0);
            NodeId k0 = l.len3(l.div(x, r[0]), l.div(y, r[1]), l.div(z, r[2]));
            d = l.mul(l.sub(k0, l.c(1)), l.mn(r[0], l.mn(r[1], r[2])));
            break;
        }
        case ShapeKind::Octahedron: {
            // Quilez's exact sdOctahedron, branch-free with selects. s: centre to vertex.
            NodeId sz = P(s, 0);
            Vec3N a = l.abs3(p);
            NodeId m = l.sub(l.add(l.add(a[0], a[1]), a[2]), sz);
            auto tail = [&](NodeId qx, NodeId qy, NodeId qz) {
                NodeId k = l.clamp(l.mul(half, l.add(l.sub(qz, qy), sz)), zero, sz);
                return l.len3(qx, l.add(l.sub(qy, sz), k), l.sub(qz, k));
            };
            NodeId c3 = l.c(3);
            NodeId fallback = l.mul(m, l.c(0.57735027f));
            NodeId dz = l.sel(l.lt(l.mul(c3, a[2]), m), tail(a[2], a[0], a[1]), fallback);
            NodeId dy = l.sel(l.lt(l.mul(c3, a[1]), m), tail(a[1], a[2], a[0]), dz);
            d = l.sel(l.lt(l.mul(c3, a[0]), m), tail(a[0], a[1], a[2]), dy);
            break;
        }
        case ShapeKind::Pyramid: {
            // Quilez's exact sdPyramid (square base 1x1 centred on the y axis, apex h above it),
            // moved down by h/2 so that it is centred at the origin like every shape: y from
            // -h/2 to h/2.
            NodeId h = P(s, 0);
            y = l.add(y, l.mul(h, half));
            NodeId m2 = l.add(l.sq(h), l.c(0.25f));
            NodeId ax = l.abs(x), az = l.abs(z);
            NodeId swap = l.lt(ax, az);
            NodeId px = l.sub(l.sel(swap, az, ax), half), pz = l.sub(l.sel(swap, ax, az), half);
            NodeId qx = pz, qy = l.sub(l.mul(h, y), l.mul(half, px)), qz = l.add(l.mul(h, px), l.mul(half, y));
            NodeId ss = l.mx(l.neg(qx), zero);
            NodeId t = l.clamp(l.div(l.sub(qy, l.mul(half, pz)), l.add(m2, l.c(0.25f))), zero, l.c(1));
            NodeId a = l.add(l.mul(m2, l.sq(l.add(qx, ss))), l.sq(qy));
            NodeId b = l.add(l.mul(m2, l.sq(l.add(qx, l.mul(half, t)))), l.sq(l.sub(qy, l.mul(m2, t))));
            NodeId cnd = l.lt(zero, l.mn(qy, l.sub(l.mul(l.neg(qx), m2), l.mul(qy, half))));
            NodeId d2 = l.sel(cnd, zero, l.mn(a, b));
            d = l.mul(l.sqrt(l.div(l.add(d2, l.sq(qz)), m2)), g.unary(Op::Sign, l.mx(qz, l.neg(y))));
            // His formula measures only to the slanted faces: below the base the nearest point
            // is on the base square, and inside the base face may be nearer than the sides.
            NodeId base = l.len3(l.mx(l.sub(ax, half), zero), y, l.mx(l.sub(az, half), zero));
            d = l.sel(l.lt(y, zero), base, l.mx(d, l.neg(y)));
            break;
        }
        case ShapeKind::HexPrism: {
            // Quilez's exact sdHexPrism with its axis along y: hexagon in xz, r = apothem.
            NodeId hh = l.mul(P(s, 0), half), r = P(s, 1);
            NodeId kx = l.c(-0.8660254f), ky = l.c(0.5f), kz = l.c(0.57735f);
            NodeId ax = l.abs(x), ay = l.abs(z);  // IQ's xy = our xz
            NodeId dk = l.mul(l.c(2), l.mn(l.add(l.mul(kx, ax), l.mul(ky, ay)), zero));
            ax = l.sub(ax, l.mul(dk, kx));
            ay = l.sub(ay, l.mul(dk, ky));
            NodeId lim = l.mul(kz, r);
            NodeId dx = l.mul(l.len2(l.sub(ax, l.clamp(ax, l.neg(lim), lim)), l.sub(ay, r)), g.unary(Op::Sign, l.sub(ay, r)));
            NodeId dy = l.sub(l.abs(y), hh);
            d = l.box2_q(dx, dy);
            break;
        }
        case ShapeKind::TriPrism: {
            // Quilez's sdTriPrism (a bound) with its axis along y; triangle in xz pointing +z.
            NodeId hh = l.mul(P(s, 0), half), r = P(s, 1);
            NodeId tri = l.sub(l.mx(l.add(l.mul(l.abs(x), l.c(0.866025f)), l.mul(z, half)), l.neg(z)), l.mul(r, half));
            d = l.mx(l.sub(l.abs(y), hh), tri);
            break;
        }
        case ShapeKind::Gyroid:
        case ShapeKind::SchwarzP: {
            // Sheet |g| / |grad g|max - thickness/2; |grad g| <= k*sqrt(3) for both surfaces.
            NodeId k = l.div(l.c(2 * kPi), P(s, 0));
            NodeId kx = l.mul(x, k), ky = l.mul(y, k), kz = l.mul(z, k);
            auto sn = [&](NodeId v) { return g.unary(Op::Sin, v); };
            auto cs = [&](NodeId v) { return g.unary(Op::Cos, v); };
            NodeId gv = s.kind == ShapeKind::Gyroid
                            ? l.add(l.add(l.mul(sn(kx), cs(ky)), l.mul(sn(ky), cs(kz))), l.mul(sn(kz), cs(kx)))
                            : l.add(l.add(cs(kx), cs(ky)), cs(kz));
            d = l.sub(l.div(l.abs(gv), l.mul(k, l.c(1.7320508f))), l.mul(P(s, 1), half));
            break;
        }
        case ShapeKind::Field:
            d = s.field(g, p);
            lip = s.bound;
            break;
        default:
            throw CompileError(s.loc, std::string("internal: not a primitive: ") + shape_kind_name(s.kind));
    }
    return Lowered{d, lip, {}};
}

// hg_sdf's fOpUnionStairs.
NodeId stairs_union(L& l, NodeId a, NodeId b, NodeId r, NodeId n) {
    NodeId s = l.div(r, n);
    NodeId u = l.sub(b, r);
    NodeId m = l.g.binary(Op::Mod, l.add(l.sub(u, a), s), l.mul(l.c(2), s));
    return l.mn(l.mn(a, b), l.mul(l.c(0.5f), l.add(l.add(u, a), l.abs(l.sub(m, s)))));
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
// child's material than the chain would. Returns nothing to keep the chain.
constexpr size_t kSpatialUnion = 8;

std::optional<Lowered> lower_union_spatial(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Graph& g = l.g;
    std::vector<glm::vec3> centre(s.children.size());
    for (size_t i = 0; i < s.children.size(); ++i) {
        const Bounds b = shape_bounds(g, *s.children[i]);
        if (!(b.finite() && b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) return std::nullopt;
        centre[i] = 0.5f * (b.lo + b.hi);
    }
    std::vector<uint32_t> order(s.children.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<uint32_t>(i);
    auto build = [&](auto&& self, uint32_t* first, uint32_t* last) -> Lowered {
        if (last - first == 1) {
            Lowered c = lower_shape(g, *s.children[*first], p, inherited);
            return Lowered{unit(g, c), 1.0f, c.m};
        }
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (const uint32_t* i = first; i != last; ++i) lo = glm::min(lo, centre[*i]), hi = glm::max(hi, centre[*i]);
        const glm::vec3 ext = hi - lo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        // Deterministic: ties in a coordinate keep the children's order.
        std::stable_sort(first, last, [&](uint32_t a, uint32_t b) { return centre[a][axis] < centre[b][axis]; });
        uint32_t* mid = first + (last - first) / 2;
        const Lowered a = self(self, first, mid), b = self(self, mid, last);  // in this order: node numbering
        return nearer(l, a, b, inherited);
    };
    return build(build, order.data(), order.data() + order.size());
}

Lowered lower_csg(L& l, const Shape& s, const Vec3N& p, const MaterialN* inherited) {
    Graph& g = l.g;
    if (s.children.empty()) return Lowered{l.c(1e20f), 1.0f, inherited ? *inherited : MaterialN{}};
    if (s.kind == ShapeKind::Union && s.children.size() >= kSpatialUnion)
        if (std::optional<Lowered> t = lower_union_spatial(l, s, p, inherited)) return *t;
    Lowered acc = lower_shape(g, *s.children[0], p, inherited);
    acc.d = unit(g, acc);
    acc.lip = 1.0f;
    for (size_t i = 1; i < s.children.size(); ++i) {
        Lowered c = lower_shape(g, *s.children[i], p, inherited);
        NodeId a = acc.d, b = unit(g, c);
        NodeId d = kNoNode;
        NodeId closer_a = kNoNode;  // material: 1 where a's material shows
        NodeId blend = kNoNode;     // smooth: weight of b's material
        auto smooth_k = [&]() { return P(s, 0); };
        bool hard_k = !s.params.empty() && g.is_const(P(s, 0)) && g.const_value(P(s, 0)) <= 0.0f;
        switch (s.kind) {
            case ShapeKind::Union:
                d = l.mn(a, b);
                closer_a = l.lt(a, b);
                break;
            case ShapeKind::Intersection:
                d = l.mx(a, b);
                closer_a = l.lt(b, a);
                break;
            case ShapeKind::Difference:
                d = l.mx(a, l.neg(b));
                closer_a = l.lt(l.neg(b), a);
                break;
            case ShapeKind::Xor:
                d = l.mx(l.mn(a, b), l.neg(l.mx(a, b)));
                closer_a = l.lt(a, b);
                break;
            case ShapeKind::SmoothUnion:
            case ShapeKind::SmoothIntersection:
            case ShapeKind::SmoothDifference: {
                // Quadratic polynomial smooth min (Quilez): equals the hard op when |a-b| >= k.
                NodeId sa = a, sb = b;
                if (s.kind == ShapeKind::SmoothIntersection) { sa = l.neg(a); sb = l.neg(b); }
                if (s.kind == ShapeKind::SmoothDifference) { sa = l.neg(a); sb = b; }
                if (hard_k) {
                    d = l.mn(sa, sb);
                    closer_a = l.lt(sa, sb);
                } else {
                    NodeId k = smooth_k();
                    NodeId h = l.div(l.mx(l.sub(k, l.abs(l.sub(sa, sb))), l.c(0)), k);
                    d = l.sub(l.mn(sa, sb), l.mul(l.mul(l.sq(h), k), l.c(0.25f)));
                    blend = l.clamp(l.add(l.c(0.5f), l.div(l.mul(l.c(0.5f), l.sub(sa, sb)), k)), l.c(0), l.c(1));
                }
                if (s.kind != ShapeKind::SmoothUnion) d = l.neg(d);
                break;
            }
            // hg_sdf's chamfers scale the diagonal term by sqrt(1/2); its gradient then reaches
            // sqrt(2) where the operands' gradients align. Halving it instead keeps the same
            // surface (same sign everywhere) and a 1-Lipschitz field.
            case ShapeKind::ChamferUnion:
                d = l.mn(l.mn(a, b), l.mul(l.sub(l.add(a, b), P(s, 0)), l.c(0.5f)));
                closer_a = l.lt(a, b);
                break;
            case ShapeKind::ChamferIntersection:
                d = l.mx(l.mx(a, b), l.mul(l.add(l.add(a, b), P(s, 0)), l.c(0.5f)));
                closer_a = l.lt(b, a);
                break;
            case ShapeKind::ChamferDifference: {
                NodeId nb = l.neg(b);
                d = l.mx(l.mx(a, nb), l.mul(l.add(l.add(a, nb), P(s, 0)), l.c(0.5f)));
                closer_a = l.lt(nb, a);
                break;
            }
            case ShapeKind::StairsUnion:
                d = stairs_union(l, a, b, P(s, 0), P(s, 1));
                closer_a = l.lt(a, b);
                break;
            case ShapeKind::StairsIntersection:
                d = l.neg(stairs_union(l, l.neg(a), l.neg(b), P(s, 0), P(s, 1)));
                closer_a = l.lt(b, a);
                break;
            case ShapeKind::StairsDifference:
                d = l.neg(stairs_union(l, l.neg(a), b, P(s, 0), P(s, 1)));
                closer_a = l.lt(l.neg(b), a);
                break;
            default:
                throw CompileError(s.loc, "internal: not a CSG operation");
        }
        if (inherited) {
            if (blend != kNoNode)
                acc.m = mix_mat(g, acc.m, c.m, blend);
            else
                acc.m = select_mat(g, closer_a, acc.m, c.m);
        }
        acc.d = d;
    }
    return acc;
}

}  // namespace

}  // namespace sdfc
