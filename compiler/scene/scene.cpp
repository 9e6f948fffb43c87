// What the scene layer gives both the interpreter and the compiler: default settings and
// materials, shape kind names, rotation matrices as IR.
#include <numbers>

#include "compiler/scene/lower.hpp"

namespace sdfc {

namespace {
constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
}

void set_default_settings(Scene& s) {
    Graph& g = *s.graph;
    auto v3 = [&](float x, float y, float z) { return Vec3N{g.constant(x), g.constant(y), g.constant(z)}; };
    s.camera.position = v3(0, 0, 5);
    s.camera.target = v3(0, 0, 0);
    s.camera.up = v3(0, 1, 0);
    s.camera.fov = g.constant(45);
    s.camera.ortho_height = g.constant(2);
    s.ambient = v3(0.05f, 0.05f, 0.05f);
    s.background = v3(0, 0, 0);
}

MaterialN default_material(Graph& g) {
    MaterialN m;
    for (int i = 0; i < kMatChannels; ++i) m[i] = g.constant(kMatChannelInfo[i].def);
    return m;
}

const char* shape_kind_name(ShapeKind k) {
    switch (k) {
#define SDFC_SHAPE(kind, ...) case ShapeKind::kind: return #kind;
#define SDFC_INNER_SHAPE(kind, ...) case ShapeKind::kind: return #kind;
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
    }
    return "?";
}

ShapeFamily shape_family(ShapeKind k) {
    switch (k) {
#define SDFC_SHAPE(kind, name, family, ...) case ShapeKind::kind: return ShapeFamily::family;
#define SDFC_INNER_SHAPE(kind, family, ...) case ShapeKind::kind: return ShapeFamily::family;
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
    }
    return ShapeFamily::Primitive;
}

size_t shape_slots(ShapeKind k) {
    switch (k) {
#define SDFC_SHAPE(kind, ...) case ShapeKind::kind: return kind##P::kSlots;
#define SDFC_INNER_SHAPE(kind, ...) case ShapeKind::kind: return kind##P::kSlots;
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
    }
    return 0;
}

std::array<NodeId, 9> rotation_xyz(Graph& g, NodeId ax, NodeId ay, NodeId az) {
    auto cs = [&](NodeId deg) {
        NodeId r = g.mulc(deg, kDeg);
        return std::pair{g.unary(Op::Cos, r), g.unary(Op::Sin, r)};
    };
    auto [cx, sx] = cs(ax);
    auto [cy, sy] = cs(ay);
    auto [cz, sz] = cs(az);
    NodeId o = g.constant(0), i = g.constant(1);
    std::array<NodeId, 9> rx{i, o, o, o, cx, g.neg(sx), o, sx, cx};
    std::array<NodeId, 9> ry{cy, o, sy, o, i, o, g.neg(sy), o, cy};
    std::array<NodeId, 9> rz{cz, g.neg(sz), o, sz, cz, o, o, o, i};
    auto matmul = [&](const std::array<NodeId, 9>& a, const std::array<NodeId, 9>& b) {
        std::array<NodeId, 9> r;
        for (int row = 0; row < 3; ++row)
            for (int col = 0; col < 3; ++col)
                r[row * 3 + col] = g.add(g.add(g.mul(a[row * 3], b[col]), g.mul(a[row * 3 + 1], b[3 + col])),
                                         g.mul(a[row * 3 + 2], b[6 + col]));
        return r;
    };
    return matmul(rz, matmul(ry, rx));  // x first, then y, then z
}

std::array<NodeId, 9> rotation_axis_angle(Graph& g, NodeId angle_deg, const Vec3N& axis) {
    NodeId len = g.ternary(Op::Length3, axis[0], axis[1], axis[2]);
    NodeId x = g.div(axis[0], len), y = g.div(axis[1], len), z = g.div(axis[2], len);
    NodeId r = g.mulc(angle_deg, kDeg);
    NodeId c = g.unary(Op::Cos, r), s = g.unary(Op::Sin, r);
    NodeId t = g.sub(g.constant(1), c);
    auto m = [&](NodeId a, NodeId b) { return g.mul(g.mul(t, a), b); };
    // Rodrigues' rotation formula.
    return {g.add(m(x, x), c),            g.sub(m(x, y), g.mul(z, s)), g.add(m(x, z), g.mul(y, s)),
            g.add(m(x, y), g.mul(z, s)), g.add(m(y, y), c),            g.sub(m(y, z), g.mul(x, s)),
            g.sub(m(x, z), g.mul(y, s)), g.add(m(y, z), g.mul(x, s)), g.add(m(z, z), c)};
}

}  // namespace sdfc
