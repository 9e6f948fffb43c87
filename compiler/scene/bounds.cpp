// Conservative bounding boxes of shapes, from constant parameters (infinite otherwise).
// Used for Lipschitz bounds of twist/bend, slice framing and the tracer's culling.
#include <algorithm>
#include <cmath>

#include "compiler/scene/lower.hpp"

namespace sdfc {
namespace {

constexpr float kInf = 1e30f;
Bounds infinite() { return Bounds{}; }
Bounds empty() { return Bounds{glm::vec3(kInf), glm::vec3(-kInf)}; }
Bounds sym(glm::vec3 e) { return Bounds{-e, e}; }
Bounds grow(Bounds b, float r) {
    for (int i = 0; i < 3; ++i) {
        if (b.lo[i] > -kInf * 0.1f) b.lo[i] -= r;
        if (b.hi[i] < kInf * 0.1f) b.hi[i] += r;
    }
    return b;
}
Bounds join(const Bounds& a, const Bounds& b) { return Bounds{glm::min(a.lo, b.lo), glm::max(a.hi, b.hi)}; }
Bounds meet(const Bounds& a, const Bounds& b) { return Bounds{glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)}; }
bool is_empty(const Bounds& b) { return b.lo.x > b.hi.x || b.lo.y > b.hi.y || b.lo.z > b.hi.z; }

}  // namespace

Bounds shape_bounds(const Graph& g, const Shape& s) {
    check_stack(s.loc);
    // Every parameter must be a constant for a finite answer.
    std::vector<float> v;
    for (NodeId n : s.params) {
        if (!g.is_const(n)) return infinite();
        v.push_back(g.const_value(n));
    }
    auto f = [&](size_t i) { return std::fabs(v.at(i)); };
    auto v3 = [&](size_t i) { return glm::vec3(v.at(i), v.at(i + 1), v.at(i + 2)); };
    auto child = [&](size_t i = 0) { return shape_bounds(g, *s.children.at(i)); };
    switch (s.kind) {
        case ShapeKind::Empty: return empty();
        case ShapeKind::Sphere: return sym(glm::vec3(f(0)));
        case ShapeKind::Box:
        case ShapeKind::RoundBox:
        case ShapeKind::BoxFrame: return sym(glm::abs(v3(0)) * 0.5f);
        case ShapeKind::Torus:
        case ShapeKind::CappedTorus: {
            size_t o = s.kind == ShapeKind::Torus ? 0 : 1;
            float R = f(o) + f(o + 1);
            return sym({R, f(o + 1), R});
        }
        case ShapeKind::Link: return sym({f(1) + f(2), f(0) * 0.5f + f(1) + f(2), f(2)});
        case ShapeKind::Cylinder:
        case ShapeKind::RoundCylinder: return sym({f(1), f(0) * 0.5f, f(1)});
        case ShapeKind::Capsule: return grow(Bounds{glm::min(v3(0), v3(3)), glm::max(v3(0), v3(3))}, f(6));
        case ShapeKind::Cone: {
            float r = std::max(f(1), f(2));
            return sym({r, f(0) * 0.5f, r});
        }
        case ShapeKind::Ellipsoid: return sym(glm::abs(v3(0)));
        case ShapeKind::Octahedron: return sym(glm::vec3(f(0)));
        case ShapeKind::Pyramid: return sym({0.5f, std::abs(f(0)) * 0.5f, 0.5f});
        case ShapeKind::HexPrism: return sym({f(1) * 1.1547006f, f(0) * 0.5f, f(1) * 1.1547006f});
        case ShapeKind::TriPrism: return sym({f(1) * 2, f(0) * 0.5f, f(1) * 2});
        case ShapeKind::Plane:
        case ShapeKind::Gyroid:
        case ShapeKind::SchwarzP:
        case ShapeKind::Field: return infinite();
        case ShapeKind::Union:
        case ShapeKind::Xor:
        case ShapeKind::SmoothUnion:
        case ShapeKind::ChamferUnion:
        case ShapeKind::StairsUnion: {
            Bounds b = empty();
            for (size_t i = 0; i < s.children.size(); ++i) b = join(b, child(i));
            float r = s.kind == ShapeKind::Union || s.kind == ShapeKind::Xor ? 0.0f : f(0);
            return is_empty(b) ? b : grow(b, r);
        }
        case ShapeKind::Intersection:
        case ShapeKind::SmoothIntersection:
        case ShapeKind::ChamferIntersection:
        case ShapeKind::StairsIntersection: {
            Bounds b = infinite();
            for (size_t i = 0; i < s.children.size(); ++i) b = meet(b, child(i));
            return b;
        }
        case ShapeKind::Difference:
        case ShapeKind::SmoothDifference:
        case ShapeKind::ChamferDifference:
        case ShapeKind::StairsDifference: return s.children.empty() ? empty() : child(0);
        case ShapeKind::Translate: {
            Bounds b = child();
            if (is_empty(b)) return b;
            return Bounds{b.lo + v3(0), b.hi + v3(0)};
        }
        case ShapeKind::Rotate:
        case ShapeKind::Mirror: {
            Bounds b = child();
            if (is_empty(b) || !b.finite()) return is_empty(b) ? b : infinite();
            glm::mat3 m(1.0f);
            if (s.kind == ShapeKind::Rotate) {
                for (int r = 0; r < 3; ++r)
                    for (int c = 0; c < 3; ++c) m[c][r] = v[r * 3 + c];
            } else {
                glm::vec3 n = v3(0);
                m = glm::mat3(1.0f) - 2.0f * glm::outerProduct(n, n);
            }
            Bounds out = empty();
            for (int i = 0; i < 8; ++i) {
                glm::vec3 c{i & 1 ? b.hi.x : b.lo.x, i & 2 ? b.hi.y : b.lo.y, i & 4 ? b.hi.z : b.lo.z};
                glm::vec3 q = m * c;
                out = join(out, Bounds{q, q});
            }
            return out;
        }
        case ShapeKind::Scale: {
            Bounds b = child();
            if (is_empty(b) || !b.finite()) return b;
            return Bounds{b.lo * v3(0), b.hi * v3(0)};
        }
        case ShapeKind::Repeat: {
            Bounds b = child();
            for (int i = 0; i < 3; ++i)
                if (v[i] != 0.0f) { b.lo[i] = -kInf; b.hi[i] = kInf; }
            return b;
        }
        case ShapeKind::RepeatFinite: {
            Bounds b = child();
            if (is_empty(b)) return b;
            for (int i = 0; i < 3; ++i) {
                float e = std::fabs(v[i]) * std::fabs(v[3 + i]);
                if (b.lo[i] > -kInf * 0.1f) b.lo[i] -= e;
                if (b.hi[i] < kInf * 0.1f) b.hi[i] += e;
            }
            return b;
        }
        case ShapeKind::PolarRepeat:
        case ShapeKind::Twist: {
            Bounds b = child();
            if (is_empty(b) || !b.finite()) return b;
            float r = std::sqrt(std::max(b.lo.x * b.lo.x, b.hi.x * b.hi.x) + std::max(b.lo.z * b.lo.z, b.hi.z * b.hi.z));
            return Bounds{{-r, b.lo.y, -r}, {r, b.hi.y, r}};
        }
        case ShapeKind::Bend: {
            Bounds b = child();
            if (is_empty(b) || !b.finite()) return b;
            float r = std::sqrt(std::max(b.lo.x * b.lo.x, b.hi.x * b.hi.x) + std::max(b.lo.y * b.lo.y, b.hi.y * b.hi.y));
            return Bounds{{-r, -r, b.lo.z}, {r, r, b.hi.z}};
        }
        case ShapeKind::Symmetry: {
            Bounds b = child();
            if (is_empty(b)) return b;
            for (int i = 0; i < 3; ++i)
                if (v[i] != 0.0f) {
                    float e = std::max(std::fabs(b.lo[i]), std::fabs(b.hi[i]));
                    b.lo[i] = -e;
                    b.hi[i] = e;
                }
            return b;
        }
        case ShapeKind::Elongate: {
            Bounds b = child();
            if (is_empty(b)) return b;
            glm::vec3 h = glm::abs(v3(0)) * 0.5f;
            return Bounds{b.lo - h, b.hi + h};
        }
        case ShapeKind::Round:
        case ShapeKind::Onion: return grow(child(), f(0));
        case ShapeKind::Displace: return grow(child(), f(0) * 1.5f);
        case ShapeKind::Material: return child();
        case ShapeKind::Choose: return join(child(0), child(1));  // (its condition is never a constant)
    }
    return infinite();
}

bool clip_regions(const Graph& g, const Shape& s, Bounds& box, std::vector<glm::vec4>& half_spaces) {
    check_stack(s.loc);
    switch (s.kind) {
        case ShapeKind::Union:
            for (const auto& c : s.children)
                if (!clip_regions(g, *c, box, half_spaces)) return false;
            return true;
        case ShapeKind::Material: return s.children.empty() || clip_regions(g, *s.children[0], box, half_spaces);
        case ShapeKind::Plane: {
            for (NodeId n : s.params)
                if (!g.is_const(n)) return false;
            const glm::vec3 n(g.const_value(s.params[0]), g.const_value(s.params[1]), g.const_value(s.params[2]));
            const float len = glm::length(n), h = g.const_value(s.params[3]);
            if (!(len > 0.0f) || !std::isfinite(len) || !std::isfinite(h)) return false;
            half_spaces.emplace_back(n / len, h);
            return true;
        }
        default: {
            const Bounds b = shape_bounds(g, s);
            if (is_empty(b)) return true;
            if (!b.finite()) return false;
            box = join(box, b);
            return true;
        }
    }
}

}  // namespace sdfc
