// Edge-collapse simplification (simplify.hpp), in rounds so the field is asked in batches:
//
//   quadrics  every vertex starts with the planes of its triangles, weighted by area
//   queue     every edge's collapse in a bucket queue by cost: the RMS distance to the
//             planes merged of the point their quadrics' sum puts it at (qef.hpp; an end or
//             the middle when better, or when the solution strays)
//   round     cheapest first, up to 1024 collapses whose neighbourhoods do not overlap are
//             taken; being independent, they are planned and checked (topology, geometry)
//             in parallel, the field is asked at their probes (the new vertex; a new
//             triangle's centroid where the surface may sag) in one batch, and those
//             within the tolerance are made, in parallel too
//   again     a collapse changes one vertex: only its edges are queued again; stale
//             entries are skipped by a version stamp. When the queue runs out, every edge
//             is queued once more (a neighbour's change may have unblocked it), at most
//             kPasses times, skipping the collapses the field refused unchanged
#include "runtime/mesh/simplify.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <unordered_map>
#include <vector>

#include "runtime/mesh/qef.hpp"

namespace sdfc::mesh {
namespace {

constexpr uint32_t kGone = ~0u;
constexpr size_t kRound = 1024;  // collapses asked of the field at once
constexpr size_t kGrain = 32;   // of them per task
constexpr size_t kMaxValence = 40;          // keeps fans, and the checks on them, small
constexpr size_t kSlot = 2 * kMaxValence + 8;  // room for one collapse's requeued edges
constexpr size_t kProbesPerTriangle = 5;       // the centroid, the new edge's middle, three inner points
constexpr size_t kProbeSlot = 1 + kProbesPerTriangle * (kMaxValence + 2);  // one collapse's probes
constexpr float kMinTurn = 0.2f;            // cosine: a triangle may turn by up to ~78 degrees
constexpr float kSliver = 0.05f;
constexpr int kPasses = 3;     // the queue made again from every edge at most this often
constexpr float kSag = 0.25f;  // of the tolerance: a triangle's centroid is asked when it may sag more            // quality (1 equilateral, 0 flat) no new triangle goes under

struct Collapse {
    double cost;
    uint32_t u, v;  // v goes into u
    glm::vec3 p;
};

// A collapse waiting its turn, small so the queue stays in cache; its point is worked out
// again when it comes up.
struct Queued {
    float cost;
    uint32_t u, v;
    uint32_t stamp;  // the sum of u's and v's versions then: versions only grow
};

// Collapses by cost: 1024 buckets over [0, tolerance], first in first out within one
// (O(1) each way; ties in the order queued, so the result is reproducible). A collapse
// dearer than the tolerance is not kept: it is planned again if its vertices change.
class Queue {
public:
    explicit Queue(float tol) : tol_(tol), b_(kBuckets) {}
    void clear() {
        for (auto& d : b_) d.clear();
        low_ = kBuckets, size_ = 0;
    }
    size_t size() const { return size_; }
    void push(const Queued& q, bool front = false) {
        if (!(q.cost <= tol_)) return;
        ++size_;
        const size_t k = std::min(kBuckets - 1, size_t(q.cost / tol_ * float(kBuckets)));
        if (front) b_[k].push_front(q);
        else b_[k].push_back(q);
        low_ = std::min(low_, k);
    }
    bool pop(Queued& out) {
        while (low_ < kBuckets && b_[low_].empty()) ++low_;
        if (low_ == kBuckets) return false;
        out = b_[low_].front();
        b_[low_].pop_front();
        --size_;
        return true;
    }

private:
    static constexpr size_t kBuckets = 1024;
    float tol_;
    std::vector<std::deque<Queued>> b_;
    size_t low_ = kBuckets, size_ = 0;
};

// 1 for an equilateral triangle, 0 for a flat one.
float quality(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const float l = glm::dot(b - a, b - a) + glm::dot(c - b, c - b) + glm::dot(a - c, a - c);
    const float area2 = glm::length(glm::cross(b - a, c - a));  // twice the area
    return l > 0.0f ? 2.0f * std::sqrt(3.0f) * area2 / l : 0.0f;
}

// The distance from p to the triangle abc (the nearest point by its Voronoi regions).
float point_triangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
    const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0f && d2 <= 0.0f) return glm::length(p - a);
    const glm::vec3 bp = p - b;
    const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0f && d4 <= d3) return glm::length(p - b);
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
    const glm::vec3 cp = p - c;
    const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0f && d5 <= d6) return glm::length(p - c);
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f)
        return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const float denom = va + vb + vc;
    if (!(std::fabs(denom) > 0.0f)) return glm::length(p - a);
    return glm::length(p - (a + ab * (vb / denom) + ac * (vc / denom)));
}

class Simplifier {
public:
    Simplifier(Mesh& m, float tol, const FieldGradient& field, const std::function<void(double)>& progress)
        : m_(m), tol_(tol), field_(field), progress_(progress) {}

    void run(SimplifyStats& st) {
        st.triangles_before = m_.triangles.size();
        const size_t nv = m_.positions.size();
        faces_.assign(nv, {});
        q_.assign(nv, Qef{});
        version_.assign(nv, 0);
        core_lock_.assign(nv, 0);
        ring_lock_.assign(nv, 0);
        dead_.assign(m_.triangles.size(), 0);
        normal_.assign(nv, glm::vec3(0.0f));
        for (uint32_t f = 0; f < m_.triangles.size(); ++f) {
            const auto& t = m_.triangles[f];
            const glm::vec3 a = m_.positions[t[0]], b = m_.positions[t[1]], c = m_.positions[t[2]];
            const glm::vec3 n = glm::cross(b - a, c - a);
            const float len = glm::length(n);
            for (uint32_t v : t) faces_[v].push_back(f), normal_[v] += n;  // by area
            if (!(len > 0.0f) || !std::isfinite(len)) continue;
            for (uint32_t v : t) q_[v].add((a + b + c) / 3.0f, n / len, 0.5 * double(len));
        }
        for (glm::vec3& n : normal_) {
            const float l = glm::length(n);
            n = l > 0.0f && std::isfinite(l) ? n / l : glm::vec3(0.0f);
        }
        for (int pass = 0; pass < kPasses; ++pass) {
            const size_t before = st.collapses;
            queue_every_edge();
            // The fraction of this pass's queue gone (the queue also grows as it goes).
            const double queued = double(std::max<size_t>(queue_.size(), 1));
            double done = 0.0;
            while (round(st)) {
                if (!progress_) continue;
                done = std::max(done, 1.0 - double(queue_.size()) / queued);
                progress_((double(pass) + std::clamp(done, 0.0, 1.0)) / kPasses);
            }
            if (st.collapses - before < st.triangles_before / 200) break;  // under 1% more
        }
        compact();
        st.triangles_after = m_.triangles.size();
    }

private:
    Mesh& m_;
    const float tol_;
    const FieldGradient& field_;
    const std::function<void(double)>& progress_;
    std::vector<std::vector<uint32_t>> faces_;  // each vertex's triangles
    std::vector<Qef> q_;
    std::vector<uint32_t> version_;  // kGone once collapsed into another
    std::vector<uint32_t> core_lock_, ring_lock_;  // the round whose collapse holds the vertex
    std::vector<uint32_t> ring_;
    std::vector<glm::vec3> slots_;  // a round's probes
    std::vector<Queued> requeue_;   // a round's collapses to queue
    std::vector<uint8_t> dead_;      // per triangle
    std::vector<glm::vec3> normal_;  // the surface's at each vertex (the field's, once moved)
    Queue queue_{tol_};
    // Collapses the field refused, by their vertices' version sum then: not queued again
    // by a later pass unless a vertex changed.
    std::unordered_map<uint64_t, uint32_t> refused_;
    static uint64_t key(uint32_t u, uint32_t v) { return u < v ? uint64_t(u) << 32 | v : uint64_t(v) << 32 | u; }
    uint32_t round_ = 0;

    Collapse plan(uint32_t u, uint32_t v) const {
        Qef e = q_[u];
        e.merge(q_[v]);
        const glm::dvec3 pu(m_.positions[u]), pv(m_.positions[v]), mid = 0.5 * (pu + pv);
        glm::dvec3 best = e.solve();
        if (!(glm::length(best - mid) <= glm::length(pu - pv))) best = mid;  // strayed (or NaN)
        double err = e.error(best);
        for (const glm::dvec3& x : {pu, pv, mid}) {
            const double ex = e.error(x);
            if (ex < err) err = ex, best = x;
        }
        const double cost = e.weight > 0.0 ? std::sqrt(err / e.weight) : 0.0;
        return {cost, u, v, glm::vec3(best)};
    }

    // Queued by the cheapest of the ends and the middle when that is within the tolerance
    // (the plan, worked out when it comes up, can only be cheaper), else by the plan.
    Queued queued(uint32_t u, uint32_t v) const {
        Qef e = q_[u];
        e.merge(q_[v]);
        const glm::dvec3 pu(m_.positions[u]), pv(m_.positions[v]);
        const double err = std::min({e.error(pu), e.error(pv), e.error(0.5 * (pu + pv))});
        double cost = e.weight > 0.0 ? std::sqrt(err / e.weight) : 0.0;
        if (!(cost <= tol_)) cost = plan(u, v).cost;
        return {float(cost), u, v, version_[u] + version_[v]};
    }

    void queue_every_edge() {
        std::vector<std::pair<uint32_t, uint32_t>> edges;
        for (uint32_t f = 0; f < m_.triangles.size(); ++f) {
            if (dead_[f]) continue;
            const auto& t = m_.triangles[f];
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
                if (a < b) edges.emplace_back(a, b);  // the other triangle has it as (b, a)
            }
        }
        std::vector<Queued> plans(edges.size());
        tbb::parallel_for(size_t(0), edges.size(), [&](size_t i) { plans[i] = queued(edges[i].first, edges[i].second); });
        queue_.clear();
        for (const Queued& q : plans) {
            const auto r = refused_.find(key(q.u, q.v));
            if (r == refused_.end() || r->second != q.stamp) queue_.push(q);
        }
    }

    bool stale(const Queued& q) const {
        return version_[q.u] == kGone || version_[q.v] == kGone || version_[q.u] + version_[q.v] != q.stamp;
    }

    void neighbours(uint32_t u, std::vector<uint32_t>& out) const {
        out.clear();
        for (uint32_t f : faces_[u])
            for (uint32_t w : m_.triangles[f])
                if (w != u) out.push_back(w);
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }

    // The topology and the geometry the collapse leaves; the field is asked after.
    bool allowed(const Collapse& c) const {
        const uint32_t u = c.u, v = c.v;
        uint32_t o[2];
        if (!opposite(u, v, o)) return false;  // not a manifold edge
        if (faces_[o[0]].size() <= 3 || faces_[o[1]].size() <= 3) return false;
        if (faces_[u].size() + faces_[v].size() - 4 > kMaxValence) return false;
        thread_local std::vector<uint32_t> nu, nv;
        neighbours(u, nu);
        neighbours(v, nv);
        size_t common = 0;
        for (size_t i = 0, j = 0; i < nu.size() && j < nv.size();) {
            if (nu[i] < nv[j]) ++i;
            else if (nv[j] < nu[i]) ++j;
            else ++common, ++i, ++j;
        }
        if (common != 2) return false;  // the link condition: else a pinch or a fold
        float near_u = INFINITY, near_v = INFINITY;
        for (uint32_t x : {u, v})
            for (uint32_t f : faces_[x]) {
                const auto& t = m_.triangles[f];
                if (x == u && (t[0] == v || t[1] == v || t[2] == v)) continue;
                if (x == v && (t[0] == u || t[1] == u || t[2] == u)) continue;
                glm::vec3 o[3], n[3];
                for (int k = 0; k < 3; ++k) {
                    o[k] = m_.positions[t[size_t(k)]];
                    n[k] = t[size_t(k)] == x ? c.p : o[k];
                }
                const glm::vec3 n0 = glm::cross(o[1] - o[0], o[2] - o[0]), n1 = glm::cross(n[1] - n[0], n[2] - n[0]);
                const float l0 = glm::length(n0), l1 = glm::length(n1);
                if (!(l1 > 0.0f) || !(glm::dot(n0, n1) > kMinTurn * l0 * l1)) return false;
                const float qn = quality(n[0], n[1], n[2]);
                if (qn < kSliver && qn < quality(o[0], o[1], o[2])) return false;
                near_u = std::min(near_u, point_triangle(m_.positions[u], n[0], n[1], n[2]));
                near_v = std::min(near_v, point_triangle(m_.positions[v], n[0], n[1], n[2]));
            }
        return near_u <= tol_ && near_v <= tol_;
    }

    // The edge's two triangles' third vertices; false if it is not in exactly two.
    bool opposite(uint32_t u, uint32_t v, uint32_t out[2]) const {
        uint32_t shared = 0;
        for (uint32_t f : faces_[u]) {
            const auto& t = m_.triangles[f];
            if (t[0] != v && t[1] != v && t[2] != v) continue;
            if (shared == 2) return false;
            for (uint32_t w : t)
                if (w != u && w != v) out[shared] = w;
            ++shared;
        }
        return shared == 2;
    }

    // A collapse changes the triangles of its core (its two vertices and the two opposite)
    // and reads those of its ring (every vertex of its triangles): two collapses are
    // independent when neither's core meets the other's ring. One pass over the ring.
    enum class Take { Taken, Blocked, Never };
    Take take(uint32_t u, uint32_t v) {
        uint32_t o[2], shared = 0;
        ring_.clear();
        for (uint32_t x : {u, v})
            for (uint32_t f : faces_[x]) {
                const auto& t = m_.triangles[f];
                if (x == u && (t[0] == v || t[1] == v || t[2] == v)) {
                    if (shared == 2) return Take::Never;  // not a manifold edge
                    for (uint32_t w : t)
                        if (w != u && w != v) o[shared] = w;
                    ++shared;
                }
                for (uint32_t w : t) {
                    if (core_lock_[w] == round_) return Take::Blocked;
                    ring_.push_back(w);
                }
            }
        if (shared != 2) return Take::Never;
        for (uint32_t x : {u, v, o[0], o[1]})
            if (ring_lock_[x] == round_) return Take::Blocked;
        for (uint32_t x : {u, v, o[0], o[1]}) core_lock_[x] = round_;
        for (uint32_t w : ring_) ring_lock_[w] = round_;
        return Take::Taken;
    }

    // Where a new triangle may leave the surface: its centroid, and, unless the triangle is
    // too small to sag by a quarter of the tolerance, the middle of the new edge after the
    // moved vertex (each new edge is that of one triangle) and three points between the
    // centroid and its corners (a triangle bridging a gap or a crease strays inside, not
    // only at the centroid). The sag is bounded by the longest edge L and the angle θ
    // between the corners' normals, an arc's L θ / 8.
    size_t probes(const Collapse& c, glm::vec3* out) const {
        size_t count = 0;
        out[count++] = c.p;
        const glm::vec3 np = merged_normal(c.u, c.v);
        for (uint32_t x : {c.u, c.v})
            for (uint32_t f : faces_[x]) {
                const auto& t = m_.triangles[f];
                const bool both = (t[0] == c.u || t[1] == c.u || t[2] == c.u) && (t[0] == c.v || t[1] == c.v || t[2] == c.v);
                if (both || (x == c.u && (t[0] == c.v || t[1] == c.v || t[2] == c.v))) continue;
                glm::vec3 p[3], n[3];
                for (int k = 0; k < 3; ++k) {
                    const uint32_t w = t[size_t(k)];
                    p[k] = w == x ? c.p : m_.positions[w];
                    n[k] = w == x ? np : normal_[w];
                }
                const float len = std::sqrt(std::max({glm::dot(p[1] - p[0], p[1] - p[0]), glm::dot(p[2] - p[1], p[2] - p[1]),
                                                       glm::dot(p[0] - p[2], p[0] - p[2])}));
                const float cos_min = std::min({glm::dot(n[0], n[1]), glm::dot(n[1], n[2]), glm::dot(n[2], n[0])});
                const float theta = std::acos(std::clamp(cos_min, -1.0f, 1.0f));
                const bool flat = len * theta * 0.125f <= kSag * tol_ && len <= tol_;
                for (int k = 0; k < 3; ++k) {
                    if (t[size_t(k)] != x) continue;
                    const int e = (k + 1) % 3;
                    if (!flat) out[count++] = 0.5f * (p[k] + p[e]);
                }
                const glm::vec3 centre = (p[0] + p[1] + p[2]) / 3.0f;
                out[count++] = centre;
                if (!flat)
                    for (int k = 0; k < 3; ++k) out[count++] = 0.5f * (centre + p[k]);
            }
        return count;
    }

    glm::vec3 merged_normal(uint32_t u, uint32_t v) const {
        const glm::vec3 s = normal_[u] + normal_[v];
        const float l = glm::length(s);
        return l > 1e-12f ? s / l : normal_[u];
    }

    bool near_surface(const Dual& d) const {
        const float g = std::sqrt(d.dx * d.dx + d.dy * d.dy + d.dz * d.dz);
        const float dist = std::fabs(d.v) / (g > 1e-6f ? g : 1.0f);
        return dist <= 0.85f * tol_;  // (kept for what lies between the probes) NaN: not
    }

    // Returns the collapses of u's edges to queue, in out (kSlot at most).
    size_t collapse(const Collapse& c, Queued* out) {
        const uint32_t u = c.u, v = c.v;
        auto drop = [&](uint32_t w, uint32_t f) {
            auto& l = faces_[w];
            l.erase(std::remove(l.begin(), l.end(), f), l.end());
        };
        for (uint32_t f : faces_[v]) {
            auto& t = m_.triangles[f];
            if (t[0] == u || t[1] == u || t[2] == u) {
                dead_[f] = 1;
                for (uint32_t w : t)
                    if (w != v) drop(w, f);
                continue;
            }
            for (uint32_t& w : t)
                if (w == v) w = u;
            faces_[u].push_back(f);
        }
        faces_[v].clear();
        faces_[v].shrink_to_fit();
        version_[v] = kGone;
        ++version_[u];
        m_.positions[u] = c.p;
        q_[u].merge(q_[v]);
        thread_local std::vector<uint32_t> nu;
        neighbours(u, nu);
        size_t n = 0;
        for (uint32_t w : nu)
            if (n < kSlot) out[n++] = queued(u, w);
        return n;
    }

    // The cheapest live collapse.
    bool next(Queued& out) {
        while (queue_.pop(out))
            if (!stale(out)) return true;
        return false;
    }

    // One round; false when nothing cheap enough is left. The collapses taken are
    // independent, so they are planned, checked and made in parallel.
    bool round(SimplifyStats& st) {
        ++round_;
        std::vector<Collapse> chosen;
        std::vector<Queued> later;  // in the order taken: by cost
        Queued q;
        while (chosen.size() < kRound && next(q)) {
            const Take t = take(q.u, q.v);
            if (t == Take::Blocked) later.push_back(q);
            if (t == Take::Taken) chosen.push_back({0.0, q.u, q.v, glm::vec3(0.0f)});
        }
        for (size_t i = later.size(); i-- > 0;) queue_.push(later[i], true);  // first next round
        if (chosen.empty()) return false;
        ++st.rounds;
        const size_t n = chosen.size();
        // Fixed slots per collapse, kept from round to round (only their counts are reset).
        slots_.resize(std::max(slots_.size(), n * kProbeSlot));
        requeue_.resize(std::max(requeue_.size(), n * kSlot));
        std::vector<glm::vec3>& slots = slots_;
        std::vector<Queued>& requeue = requeue_;
        std::vector<size_t> count(n, 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kGrain), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i < r.end(); ++i) {
                Collapse& c = chosen[i];
                c = plan(c.u, c.v);
                if (allowed(c)) count[i] = probes(c, &slots[i * kProbeSlot]);
            }
        });
        std::vector<size_t> first(n + 1, 0);
        for (size_t i = 0; i < n; ++i) first[i + 1] = first[i] + count[i];
        std::vector<glm::vec3> pts(first[n]);
        for (size_t i = 0; i < n; ++i) std::copy_n(slots.data() + i * kProbeSlot, count[i], pts.data() + first[i]);
        std::vector<Dual> d(pts.size());
        field_(pts.data(), pts.size(), d.data());
        std::vector<uint8_t> make(n, 0);
        for (size_t i = 0; i < n; ++i) {
            if (!count[i]) continue;  // its topology or geometry refused it
            bool ok = true;
            for (size_t j = first[i]; j < first[i + 1] && ok; ++j) ok = near_surface(d[j]);
            if (ok) {
                make[i] = 1;
                continue;
            }
            ++st.refused_by_field;
            refused_[key(chosen[i].u, chosen[i].v)] = version_[chosen[i].u] + version_[chosen[i].v];
        }
        std::vector<size_t> queued_count(n, 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kGrain), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i < r.end(); ++i) {
                if (!make[i]) continue;
                const Collapse& c = chosen[i];
                const Dual& g = d[first[i]];
                const glm::vec3 grad(g.dx, g.dy, g.dz);
                const float gl = glm::length(grad);
                normal_[c.u] = gl > 1e-12f && std::isfinite(gl) ? grad / gl : merged_normal(c.u, c.v);
                queued_count[i] = collapse(c, &requeue[i * kSlot]);
            }
        });
        for (size_t i = 0; i < n; ++i) {
            st.collapses += make[i];
            for (size_t j = 0; j < queued_count[i]; ++j) queue_.push(requeue[i * kSlot + j]);
        }
        return true;
    }

    // Drops the collapsed vertices and triangles, renumbering the rest in order.
    void compact() {
        std::vector<uint32_t> id(m_.positions.size(), kGone);
        std::vector<glm::vec3> pos;
        for (uint32_t v = 0; v < m_.positions.size(); ++v)
            if (version_[v] != kGone && !faces_[v].empty()) id[v] = uint32_t(pos.size()), pos.push_back(m_.positions[v]);
        std::vector<std::array<uint32_t, 3>> tris;
        for (uint32_t f = 0; f < m_.triangles.size(); ++f)
            if (!dead_[f]) {
                const auto& t = m_.triangles[f];
                tris.push_back({id[t[0]], id[t[1]], id[t[2]]});
            }
        m_.positions = std::move(pos);
        m_.triangles = std::move(tris);
        m_.colors.clear();
    }

};

}  // namespace

void simplify_mesh(Mesh& m, float tolerance, const FieldGradient& field, SimplifyStats* stats,
                   const std::function<void(double)>& progress) {
    SimplifyStats st;
    if (m.triangles.empty() || !(tolerance > 0.0f)) {
        st.triangles_before = st.triangles_after = m.triangles.size();
        if (stats) *stats = st;
        return;
    }
    Simplifier(m, tolerance, field, progress).run(st);
    if (stats) *stats = st;
}

}  // namespace sdfc::mesh
