// The primitives of shapes.def (LANGUAGE.md section 5): each one's distance with its
// Lipschitz bound, then its bounding box. Formulas follow Inigo Quilez's distance-function
// list (iquilezles.org, "distfunctions") unless a comment says otherwise. Every shape is
// centred at the origin; l.half and l.zero are the constants 0.5 and 0.
#include <algorithm>
#include <cmath>

#include "compiler/scene/shape_lowering.hpp"

namespace sdfc::shapes {

namespace {
Lowered exact(NodeId d) { return Lowered{d, 1.0f, {}}; }
}  // namespace

Lowered lower_Empty(L& l, const Shape&, const Vec3N&) { return exact(l.c(1e20f)); }
Bounds bounds_Empty(const BoundsIn&) { return empty(); }

Lowered lower_Sphere(L& l, const Shape& s, const Vec3N& p) {
    return exact(l.sub(l.len3(p[0], p[1], p[2]), P(s, SphereP::r)));
}
Bounds bounds_Sphere(const BoundsIn& b) { return sym(glm::vec3(b.f(SphereP::r))); }

// 2D profiles: exact in the x-y plane, so exact as prisms along z.
Lowered lower_Circle(L& l, const Shape& s, const Vec3N& p) { return exact(l.sub(l.len2(p[0], p[1]), P(s, CircleP::r))); }
Bounds bounds_Circle(const BoundsIn& b) { return Bounds{{-b.f(CircleP::r), -b.f(CircleP::r), -kInf}, {b.f(CircleP::r), b.f(CircleP::r), kInf}}; }

Lowered lower_Square(L& l, const Shape& s, const Vec3N& p) {
    const NodeId w = P(s, SquareP::size), h = P(s, SquareP::size_y_);
    return exact(l.box2_q(l.sub(l.abs(p[0]), l.mul(w, l.half)), l.sub(l.abs(p[1]), l.mul(h, l.half))));
}
Bounds bounds_Square(const BoundsIn& b) {
    const float w = 0.5f * std::fabs(b.v.at(SquareP::size)), h = 0.5f * std::fabs(b.v.at(SquareP::size_y_));
    return Bounds{{-w, -h, -kInf}, {w, h, kInf}};
}

// Quilez's sdPolygon, unrolled over the edges: the nearest edge's distance, signed by the
// crossings' parity (even-odd: a self-crossing outline alternates inside and outside).
Lowered lower_Polygon(L& l, const Shape& s, const Vec3N& p) {
    Graph& g = l.g;
    const size_t n = s.params.size() / 2;
    auto vx = [&](size_t i) { return s.params[2 * i]; };
    auto vy = [&](size_t i) { return s.params[2 * i + 1]; };
    const NodeId dx0 = l.sub(p[0], vx(0)), dy0 = l.sub(p[1], vy(0));
    NodeId d = l.add(l.mul(dx0, dx0), l.mul(dy0, dy0));
    NodeId odd = l.c(0.0f);
    for (size_t i = 0; i < n; ++i) {
        const size_t j = (i + n - 1) % n;
        const NodeId ex = l.sub(vx(j), vx(i)), ey = l.sub(vy(j), vy(i));
        const NodeId wx = l.sub(p[0], vx(i)), wy = l.sub(p[1], vy(i));
        const NodeId ee = l.mx(l.add(l.mul(ex, ex), l.mul(ey, ey)), l.c(1e-30f));
        const NodeId t = l.clamp(l.div(l.add(l.mul(wx, ex), l.mul(wy, ey)), ee), l.c(0.0f), l.c(1.0f));
        const NodeId bx = l.sub(wx, l.mul(ex, t)), by = l.sub(wy, l.mul(ey, t));
        d = l.mn(d, l.add(l.mul(bx, bx), l.mul(by, by)));
        const NodeId c1 = g.binary(Op::Le, vy(i), p[1]), c2 = l.lt(p[1], vy(j)), c3 = l.lt(l.mul(ey, wx), l.mul(ex, wy));
        const NodeId all = g.binary(Op::And, g.binary(Op::And, c1, c2), c3);
        const NodeId none = g.binary(Op::And, g.binary(Op::And, g.unary(Op::Not, c1), g.unary(Op::Not, c2)), g.unary(Op::Not, c3));
        odd = g.binary(Op::Ne, odd, g.binary(Op::Or, all, none));
    }
    return exact(l.mul(l.sel(odd, l.c(-1.0f), l.c(1.0f)), l.sqrt(d)));
}
Bounds bounds_Polygon(const BoundsIn& b) {
    glm::vec2 lo(kInf), hi(-kInf);
    for (size_t i = 0; i + 1 < b.v.size(); i += 2) {
        const glm::vec2 q(b.v[i], b.v[i + 1]);
        if (!std::isfinite(q.x) || !std::isfinite(q.y)) return infinite();
        lo = glm::min(lo, q), hi = glm::max(hi, q);
    }
    if (b.v.size() < 2) return infinite();
    return Bounds{{lo.x, lo.y, -kInf}, {hi.x, hi.y, kInf}};
}

Lowered lower_Box(L& l, const Shape& s, const Vec3N& p) {
    Vec3N b = P3(s, BoxP::size), a = l.abs3(p);
    NodeId half = l.half;
    return exact(l.box_q({l.sub(a[0], l.mul(b[0], half)), l.sub(a[1], l.mul(b[1], half)), l.sub(a[2], l.mul(b[2], half))}));
}
Bounds bounds_Box(const BoundsIn& b) { return sym(glm::abs(b.v3(BoxP::size)) * 0.5f); }

Lowered lower_RoundBox(L& l, const Shape& s, const Vec3N& p) {
    Vec3N b = P3(s, RoundBoxP::size), a = l.abs3(p);
    // A radius over half the smallest side would shrink the box: at most that (a sphere for
    // a cube), so the full size is kept.
    NodeId r = l.mn(P(s, RoundBoxP::r), l.mul(l.mn(l.mn(b[0], b[1]), b[2]), l.half));
    Vec3N q;
    for (int i = 0; i < 3; ++i) q[i] = l.add(l.sub(a[i], l.mul(b[i], l.half)), r);
    return exact(l.sub(l.box_q(q), r));
}
Bounds bounds_RoundBox(const BoundsIn& b) { return sym(glm::abs(b.v3(RoundBoxP::size)) * 0.5f); }

Lowered lower_BoxFrame(L& l, const Shape& s, const Vec3N& p) {
    // Quilez's sdBoxFrame makes bars 2e thick; ours are `e` thick.
    Vec3N b = P3(s, BoxFrameP::size), a = l.abs3(p);
    // Bars at most half the smallest side thick (then they fill the box), as round_box's radius.
    NodeId e = l.mul(l.mn(P(s, BoxFrameP::e), l.mul(l.mn(l.mn(b[0], b[1]), b[2]), l.half)), l.half);
    Vec3N pp, q;
    for (int i = 0; i < 3; ++i) {
        pp[i] = l.sub(a[i], l.mul(b[i], l.half));
        q[i] = l.sub(l.abs(l.add(pp[i], e)), e);
    }
    return exact(l.mn(l.mn(l.box_q({pp[0], q[1], q[2]}), l.box_q({q[0], pp[1], q[2]})), l.box_q({q[0], q[1], pp[2]})));
}
Bounds bounds_BoxFrame(const BoundsIn& b) { return sym(glm::abs(b.v3(BoxFrameP::size)) * 0.5f); }

namespace {
Bounds ring_bounds(const BoundsIn& b, size_t major, size_t minor) {
    float R = b.f(major) + b.f(minor);
    return sym({R, b.f(minor), R});
}
}  // namespace

Lowered lower_Torus(L& l, const Shape& s, const Vec3N& p) {
    return exact(l.sub(l.len2(l.sub(l.len2(p[0], p[2]), P(s, TorusP::major)), p[1]), P(s, TorusP::minor)));
}
Bounds bounds_Torus(const BoundsIn& b) { return ring_bounds(b, TorusP::major, TorusP::minor); }

Lowered lower_CappedTorus(L& l, const Shape& s, const Vec3N& p) {
    // Quilez's sdCappedTorus with the ring in the xz-plane (like torus) and the arc of
    // `angle` degrees symmetric about +z: his (x, y, z) are our (|x|, z, y).
    // The angle is clamped to [0, 360] (a time-dependent one can leave it), and sin of
    // the half angle to >= 0: sin(180 deg) in floats is -8.7e-8, which made the branch
    // test flip on the plane x = 0 of a full (360 degree) ring.
    Graph& g = l.g;
    NodeId zero = l.zero;
    NodeId an = l.mul(l.clamp(P(s, CappedTorusP::angle), zero, l.c(360.0f)), l.c(0.5f * kDeg));
    NodeId sx = l.mx(g.unary(Op::Sin, an), zero), sy = g.unary(Op::Cos, an);
    NodeId qx = l.abs(p[0]), qy = p[2];
    NodeId ra = P(s, CappedTorusP::major), rb = P(s, CappedTorusP::minor);
    NodeId k = l.sel(l.lt(l.mul(sx, qy), l.mul(sy, qx)), l.add(l.mul(qx, sx), l.mul(qy, sy)), l.len2(qx, qy));
    NodeId dd = l.add(l.add(l.add(l.sq(qx), l.sq(qy)), l.sq(p[1])), l.sub(l.sq(ra), l.mul(l.mul(l.c(2), ra), k)));
    return exact(l.sub(l.sqrt(l.mx(dd, zero)), rb));
}
Bounds bounds_CappedTorus(const BoundsIn& b) { return ring_bounds(b, CappedTorusP::major, CappedTorusP::minor); }

Lowered lower_Link(L& l, const Shape& s, const Vec3N& p) {
    // Quilez's sdLink: straight sections along y of total length `length`, ring in xy.
    NodeId le = l.mul(P(s, LinkP::length), l.half);
    NodeId qy = l.mx(l.sub(l.abs(p[1]), le), l.zero);
    return exact(l.sub(l.len2(l.sub(l.len2(p[0], qy), P(s, LinkP::major)), p[2]), P(s, LinkP::minor)));
}
Bounds bounds_Link(const BoundsIn& b) {
    const float le = b.f(LinkP::length), ra = b.f(LinkP::major), rb = b.f(LinkP::minor);
    return sym({ra + rb, le * 0.5f + ra + rb, rb});
}

Lowered lower_Cylinder(L& l, const Shape& s, const Vec3N& p) {
    NodeId dx = l.sub(l.len2(p[0], p[2]), P(s, CylinderP::r));
    NodeId dy = l.sub(l.abs(p[1]), l.mul(P(s, CylinderP::h), l.half));
    return exact(l.box2_q(dx, dy));
}
Bounds bounds_Cylinder(const BoundsIn& b) { return sym({b.f(CylinderP::r), b.f(CylinderP::h) * 0.5f, b.f(CylinderP::r)}); }

Lowered lower_RoundCylinder(L& l, const Shape& s, const Vec3N& p) {
    // An edge over the radius or half the height would shrink the cylinder: at most those.
    NodeId e = l.mn(P(s, RoundCylinderP::edge), l.mn(P(s, RoundCylinderP::r), l.mul(P(s, RoundCylinderP::h), l.half)));
    NodeId dx = l.add(l.sub(l.len2(p[0], p[2]), P(s, RoundCylinderP::r)), e);
    NodeId dy = l.add(l.sub(l.abs(p[1]), l.mul(P(s, RoundCylinderP::h), l.half)), e);
    return exact(l.sub(l.box2_q(dx, dy), e));
}
Bounds bounds_RoundCylinder(const BoundsIn& b) {
    return sym({b.f(RoundCylinderP::r), b.f(RoundCylinderP::h) * 0.5f, b.f(RoundCylinderP::r)});
}

Lowered lower_Capsule(L& l, const Shape& s, const Vec3N& p) {
    Graph& g = l.g;
    NodeId zero = l.zero;
    Vec3N a = P3(s, CapsuleP::a), b = P3(s, CapsuleP::b);
    Vec3N pa = l.sub3(p, a), ba = l.sub3(b, a);
    NodeId bb = l.dot3(ba, ba);
    NodeId h = (g.is_const(bb) && g.const_value(bb) == 0.0f) ? zero : l.clamp(l.div(l.dot3(pa, ba), bb), zero, l.c(1));
    return exact(l.sub(l.len3(l.sub(pa[0], l.mul(ba[0], h)), l.sub(pa[1], l.mul(ba[1], h)), l.sub(pa[2], l.mul(ba[2], h))),
                       P(s, CapsuleP::r)));
}
Bounds bounds_Capsule(const BoundsIn& b) {
    const glm::vec3 a = b.v3(CapsuleP::a), e = b.v3(CapsuleP::b);
    return grow(Bounds{glm::min(a, e), glm::max(a, e)}, b.f(CapsuleP::r));
}

Lowered lower_Cone(L& l, const Shape& s, const Vec3N& p) {
    // Quilez's sdCappedCone (exact): base radius r1 at y = -h/2, top radius r2 at +h/2.
    Graph& g = l.g;
    NodeId zero = l.zero;
    NodeId h = l.mul(P(s, ConeP::h), l.half), r1 = P(s, ConeP::r1), r2 = P(s, ConeP::r2);
    NodeId qx = l.len2(p[0], p[2]), qy = p[1];
    NodeId k1x = r2, k1y = h, k2x = l.sub(r2, r1), k2y = l.mul(l.c(2), h);
    NodeId cax = l.sub(qx, l.mn(qx, l.sel(l.lt(qy, zero), r1, r2)));
    NodeId cay = l.sub(l.abs(qy), h);
    // (floored: a flat cylinder, h = 0 and r1 = r2, has k2 = 0 and would divide 0 by 0)
    NodeId k2k2 = l.mx(l.add(l.sq(k2x), l.sq(k2y)), l.c(1e-30f));
    NodeId t = l.clamp(l.div(l.add(l.mul(l.sub(k1x, qx), k2x), l.mul(l.sub(k1y, qy), k2y)), k2k2), zero, l.c(1));
    NodeId cbx = l.add(l.sub(qx, k1x), l.mul(k2x, t));
    NodeId cby = l.add(l.sub(qy, k1y), l.mul(k2y, t));
    NodeId sgn = l.sel(g.binary(Op::And, l.lt(cbx, zero), l.lt(cay, zero)), l.c(-1), l.c(1));
    return exact(l.mul(sgn, l.sqrt(l.mn(l.add(l.sq(cax), l.sq(cay)), l.add(l.sq(cbx), l.sq(cby))))));
}
Bounds bounds_Cone(const BoundsIn& b) {
    float r = std::max(b.f(ConeP::r1), b.f(ConeP::r2));
    return sym({r, b.f(ConeP::h) * 0.5f, r});
}

Lowered lower_Plane(L& l, const Shape& s, const Vec3N& p) {
    Vec3N n = P3(s, PlaneP::normal);
    NodeId len = l.len3(n[0], n[1], n[2]);
    return exact(l.sub(l.div(l.dot3(p, n), len), P(s, PlaneP::offset)));
}
Bounds bounds_Plane(const BoundsIn&) { return infinite(); }

Lowered lower_Ellipsoid(L& l, const Shape& s, const Vec3N& p) {
    // (length(p / r) - 1) * min(r): 1-Lipschitz, exact along the shortest axis, a bound
    // elsewhere. (Quilez's k0 (k0 - 1) / k1 is tighter near the surface but its gradient
    // reaches several times 1 near the centre of elongated ellipsoids.)
    Vec3N r = P3(s, EllipsoidP::radii);
    NodeId k0 = l.len3(l.div(p[0], r[0]), l.div(p[1], r[1]), l.div(p[2], r[2]));
    return exact(l.mul(l.sub(k0, l.c(1)), l.mn(r[0], l.mn(r[1], r[2]))));
}
Bounds bounds_Ellipsoid(const BoundsIn& b) { return sym(glm::abs(b.v3(EllipsoidP::radii))); }

Lowered lower_Octahedron(L& l, const Shape& s, const Vec3N& p) {
    // Quilez's exact sdOctahedron, branch-free with selects. s: centre to vertex.
    NodeId sz = P(s, OctahedronP::s);
    Vec3N a = l.abs3(p);
    NodeId m = l.sub(l.add(l.add(a[0], a[1]), a[2]), sz);
    auto tail = [&](NodeId qx, NodeId qy, NodeId qz) {
        NodeId k = l.clamp(l.mul(l.half, l.add(l.sub(qz, qy), sz)), l.zero, sz);
        return l.len3(qx, l.add(l.sub(qy, sz), k), l.sub(qz, k));
    };
    NodeId c3 = l.c(3);
    NodeId fallback = l.mul(m, l.c(0.57735027f));
    NodeId dz = l.sel(l.lt(l.mul(c3, a[2]), m), tail(a[2], a[0], a[1]), fallback);
    NodeId dy = l.sel(l.lt(l.mul(c3, a[1]), m), tail(a[1], a[2], a[0]), dz);
    return exact(l.sel(l.lt(l.mul(c3, a[0]), m), tail(a[0], a[1], a[2]), dy));
}
Bounds bounds_Octahedron(const BoundsIn& b) { return sym(glm::vec3(b.f(OctahedronP::s))); }

Lowered lower_Pyramid(L& l, const Shape& s, const Vec3N& p) {
    // Quilez's exact sdPyramid (square base 1x1 centred on the y axis, apex h above it),
    // moved down by h/2 so that it is centred at the origin like every shape: y from
    // -h/2 to h/2.
    Graph& g = l.g;
    NodeId half = l.half, zero = l.zero;
    NodeId x = p[0], z = p[2];
    NodeId h = P(s, PyramidP::h);
    NodeId y = l.add(p[1], l.mul(h, half));
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
    NodeId d = l.mul(l.sqrt(l.div(l.add(d2, l.sq(qz)), m2)), g.unary(Op::Sign, l.mx(qz, l.neg(y))));
    // His formula measures only to the slanted faces: below the base the nearest point
    // is on the base square, and inside the base face may be nearer than the sides.
    NodeId base = l.len3(l.mx(l.sub(ax, half), zero), y, l.mx(l.sub(az, half), zero));
    return exact(l.sel(l.lt(y, zero), base, l.mx(d, l.neg(y))));
}
Bounds bounds_Pyramid(const BoundsIn& b) { return sym({0.5f, std::abs(b.f(PyramidP::h)) * 0.5f, 0.5f}); }

Lowered lower_HexPrism(L& l, const Shape& s, const Vec3N& p) {
    // Quilez's exact sdHexPrism with its axis along y: hexagon in xz, r = apothem.
    Graph& g = l.g;
    NodeId zero = l.zero;
    NodeId hh = l.mul(P(s, HexPrismP::h), l.half), r = P(s, HexPrismP::r);
    NodeId kx = l.c(-0.8660254f), ky = l.c(0.5f), kz = l.c(0.57735f);
    NodeId ax = l.abs(p[0]), ay = l.abs(p[2]);  // IQ's xy = our xz
    NodeId dk = l.mul(l.c(2), l.mn(l.add(l.mul(kx, ax), l.mul(ky, ay)), zero));
    ax = l.sub(ax, l.mul(dk, kx));
    ay = l.sub(ay, l.mul(dk, ky));
    NodeId lim = l.mul(kz, r);
    NodeId dx = l.mul(l.len2(l.sub(ax, l.clamp(ax, l.neg(lim), lim)), l.sub(ay, r)), g.unary(Op::Sign, l.sub(ay, r)));
    NodeId dy = l.sub(l.abs(p[1]), hh);
    return exact(l.box2_q(dx, dy));
}
Bounds bounds_HexPrism(const BoundsIn& b) {
    return sym({b.f(HexPrismP::r) * 1.1547006f, b.f(HexPrismP::h) * 0.5f, b.f(HexPrismP::r) * 1.1547006f});
}

Lowered lower_TriPrism(L& l, const Shape& s, const Vec3N& p) {
    // Quilez's sdTriPrism (a bound) with its axis along y; triangle in xz pointing +z.
    NodeId half = l.half;
    NodeId hh = l.mul(P(s, TriPrismP::h), half), r = P(s, TriPrismP::r);
    NodeId tri = l.sub(l.mx(l.add(l.mul(l.abs(p[0]), l.c(0.866025f)), l.mul(p[2], half)), l.neg(p[2])), l.mul(r, half));
    return exact(l.mx(l.sub(l.abs(p[1]), hh), tri));
}
Bounds bounds_TriPrism(const BoundsIn& b) { return sym({b.f(TriPrismP::r) * 2, b.f(TriPrismP::h) * 0.5f, b.f(TriPrismP::r) * 2}); }

namespace {
// Sheet |g| / |grad g|max - thickness/2; |grad g| <= k*sqrt(3) for both surfaces.
Lowered triply_periodic(L& l, const Shape& s, const Vec3N& p, bool gyroid) {
    static_assert(size_t(GyroidP::period) == SchwarzPP::period && size_t(GyroidP::thickness) == SchwarzPP::thickness);
    Graph& g = l.g;
    NodeId k = l.div(l.c(2 * kPi), P(s, GyroidP::period));
    NodeId kx = l.mul(p[0], k), ky = l.mul(p[1], k), kz = l.mul(p[2], k);
    auto sn = [&](NodeId v) { return g.unary(Op::Sin, v); };
    auto cs = [&](NodeId v) { return g.unary(Op::Cos, v); };
    NodeId gv = gyroid ? l.add(l.add(l.mul(sn(kx), cs(ky)), l.mul(sn(ky), cs(kz))), l.mul(sn(kz), cs(kx)))
                       : l.add(l.add(cs(kx), cs(ky)), cs(kz));
    return exact(l.sub(l.div(l.abs(gv), l.mul(k, l.c(1.7320508f))), l.mul(P(s, GyroidP::thickness), l.half)));
}
}  // namespace

Lowered lower_Gyroid(L& l, const Shape& s, const Vec3N& p) { return triply_periodic(l, s, p, true); }
Bounds bounds_Gyroid(const BoundsIn&) { return infinite(); }

Lowered lower_SchwarzP(L& l, const Shape& s, const Vec3N& p) { return triply_periodic(l, s, p, false); }
Bounds bounds_SchwarzP(const BoundsIn&) { return infinite(); }

// A field's body as the interpreter evaluates it, with the Lipschitz bound the user claims.
Lowered lower_Field(L& l, const Shape& s, const Vec3N& p) { return Lowered{s.field(l.g, p), s.bound, {}}; }
Bounds bounds_Field(const BoundsIn&) { return infinite(); }

}  // namespace sdfc::shapes
