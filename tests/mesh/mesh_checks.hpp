// What a mesh must be, measured: closed and consistently oriented (every edge in exactly two
// triangles, once each way), its Euler characteristic, enclosed volume, distance of its
// vertices from the surface, and whether any two triangles intersect.
#pragma once
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include "runtime/eval/vm.hpp"
#include "runtime/mesh/mesh.hpp"

namespace sdfc::test {

// Directed edges that do not appear exactly once with their reverse exactly once: 0 for a
// closed, oriented 2-manifold surface (in its edges).
inline size_t bad_edges(const mesh::Mesh& m) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) ++directed[{t[size_t(k)], t[size_t((k + 1) % 3)]}];
    size_t bad = 0;
    for (const auto& [e, n] : directed) {
        auto rev = directed.find({e.second, e.first});
        if (n != 1 || rev == directed.end() || rev->second != 1) ++bad;
    }
    return bad;
}

// Vertices whose triangles do not form one fan (a pinch): 0 for a manifold.
inline size_t pinched_vertices(const mesh::Mesh& m) {
    std::map<uint32_t, std::map<uint32_t, uint32_t>> next;  // vertex -> (a -> b) for each triangle (v, a, b)
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) next[t[size_t(k)]][t[size_t((k + 1) % 3)]] = t[size_t((k + 2) % 3)];
    size_t bad = 0;
    for (const auto& [v, fan] : next) {
        uint32_t a = fan.begin()->first;
        size_t steps = 0;
        do {
            auto it = fan.find(a);
            if (it == fan.end()) break;
            a = it->second;
            ++steps;
        } while (a != fan.begin()->first && steps <= fan.size());
        if (steps != fan.size()) ++bad;
    }
    return bad;
}

inline long euler(const mesh::Mesh& m) {
    std::set<std::pair<uint32_t, uint32_t>> edges;
    std::set<uint32_t> used;
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
            edges.insert({std::min(a, b), std::max(a, b)});
            used.insert(a);
        }
    return long(used.size()) - long(edges.size()) + long(m.triangles.size());
}

inline double volume(const mesh::Mesh& m) {
    double v = 0.0;
    for (const auto& t : m.triangles) {
        const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        v += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    return v;
}

// The largest |distance| at the mesh's vertices.
inline float max_vertex_distance(const mesh::Mesh& m, const CompiledScene& cs) {
    Evaluator ev(cs.distance);
    float worst = 0.0f;
    for (const glm::vec3& p : m.positions) worst = std::max(worst, std::fabs(ev.eval1(p.x, p.y, p.z)));
    return worst;
}

// The distance from p to the nearest vertex.
inline float nearest_vertex(const mesh::Mesh& m, glm::vec3 p) {
    float best = INFINITY;
    for (const glm::vec3& v : m.positions) best = std::min(best, glm::length(v - p));
    return best;
}

namespace detail {
// Whether segment pq crosses triangle abc (Moller-Trumbore, strict: touching is not crossing).
inline bool segment_hits(glm::dvec3 p, glm::dvec3 q, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
    const glm::dvec3 d = q - p, e1 = b - a, e2 = c - a, h = glm::cross(d, e2);
    const double det = glm::dot(e1, h);
    if (std::fabs(det) < 1e-18) return false;
    const double f = 1.0 / det;
    const glm::dvec3 s = p - a;
    const double u = f * glm::dot(s, h);
    if (u <= 1e-9 || u >= 1.0 - 1e-9) return false;
    const glm::dvec3 qv = glm::cross(s, e1);
    const double v = f * glm::dot(d, qv);
    if (v <= 1e-9 || u + v >= 1.0 - 1e-9) return false;
    const double t = f * glm::dot(e2, qv);
    return t > 1e-9 && t < 1.0 - 1e-9;
}
}  // namespace detail

// Pairs of triangles sharing no vertex where an edge of one passes through the other
// (quadratic: for small meshes).
inline size_t intersecting_pairs(const mesh::Mesh& m) {
    const size_t n = m.triangles.size();
    std::vector<glm::vec3> lo(n), hi(n);
    for (size_t i = 0; i < n; ++i) {
        const auto& t = m.triangles[i];
        lo[i] = glm::min(glm::min(m.positions[t[0]], m.positions[t[1]]), m.positions[t[2]]);
        hi[i] = glm::max(glm::max(m.positions[t[0]], m.positions[t[1]]), m.positions[t[2]]);
    }
    size_t hits = 0;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n; ++j) {
            if (glm::any(glm::lessThan(hi[i], lo[j])) || glm::any(glm::lessThan(hi[j], lo[i]))) continue;
            const auto &A = m.triangles[i], &B = m.triangles[j];
            bool shared = false;
            for (uint32_t a : A)
                for (uint32_t b : B) shared |= a == b;
            if (shared) continue;
            auto crosses = [&](const std::array<uint32_t, 3>& s, const std::array<uint32_t, 3>& t) {
                for (int k = 0; k < 3; ++k)
                    if (detail::segment_hits(m.positions[s[size_t(k)]], m.positions[s[size_t((k + 1) % 3)]], m.positions[t[0]],
                                             m.positions[t[1]], m.positions[t[2]]))
                        return true;
                return false;
            };
            if (crosses(A, B) || crosses(B, A)) ++hits;
        }
    return hits;
}

}  // namespace sdfc::test
