// Simplification (runtime/mesh/simplify.cpp): far fewer triangles, still closed, oriented
// and manifold, of the same topology, within the tolerance of the surface at the vertices
// and all over the triangles, corners kept, no triangles crossing.
#include <catch2/catch.hpp>

#include "mesh_checks.hpp"
#include "runtime/mesh/simplify.hpp"
#include "support.hpp"

using namespace sdfc;
using namespace sdfc::test;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Simplified {
    std::unique_ptr<Compiled> c;
    mesh::Mesh m;
    mesh::MeshStats st;
    float cell = 0.0f, tol = 0.0f;
};

// Meshed at `resolution` and simplified to `tol_cells` cells.
Simplified simplify_text(const std::string& src, int resolution, float tol_cells, bool colors = false) {
    Simplified r;
    r.c = compile_text(src);
    mesh::MeshOptions o;
    REQUIRE(mesh::default_box(r.c->cs, o.lo, o.hi));
    o.resolution = resolution;
    const glm::vec3 ext = o.hi - o.lo;
    r.cell = std::max({ext.x, ext.y, ext.z}) / float(resolution);
    r.tol = tol_cells * r.cell;
    o.simplify = r.tol;
    o.colors = colors;
    r.m = mesh::mesh_scene(r.c->cs, o, &r.st);
    return r;
}

void check_closed_manifold(const mesh::Mesh& m) {
    REQUIRE(!m.triangles.empty());
    CHECK(bad_edges(m) == 0);
    CHECK(pinched_vertices(m) == 0);
}

// The largest |distance| at the triangles' centroids, edges' middles and the points between
// (a barycentric grid of sixths).
float max_centroid_distance(const mesh::Mesh& m, const CompiledScene& cs) {
    Evaluator ev(cs.distance);
    float worst = 0.0f;
    for (const auto& t : m.triangles)
        for (int i = 0; i <= 6; ++i)
            for (int j = 0; i + j <= 6; ++j) {
                const float a = float(i) / 6.0f, b = float(j) / 6.0f;
                const glm::vec3 p = m.positions[t[0]] * (1.0f - a - b) + m.positions[t[1]] * a + m.positions[t[2]] * b;
                worst = std::max(worst, std::fabs(ev.eval1(p.x, p.y, p.z)));
            }
    return worst;
}

}  // namespace

TEST_CASE("simplify: a sphere keeps its shape with a tenth of the triangles", "[mesh]") {
    Simplified s = simplify_text("sphere(1);", 48, 0.25f);
    check_closed_manifold(s.m);
    CHECK(euler(s.m) == 2);
    CHECK(s.m.triangles.size() * 10 < s.st.unsimplified_triangles);
    CHECK(s.st.triangles == s.m.triangles.size());
    CHECK(max_vertex_distance(s.m, s.c->cs) <= s.tol);
    CHECK(max_centroid_distance(s.m, s.c->cs) <= s.tol);
    // Off by at most the tolerance times the area (3 %); the chords lie inside.
    CHECK(volume(s.m) == Approx(4.0 / 3.0 * kPi).epsilon(0.02));
    CHECK(volume(s.m) < 4.0 / 3.0 * kPi);
}

TEST_CASE("simplify: a torus's triangles lie within the tolerance all over, not only at the probes", "[mesh]") {
    // A tolerance of 0.002 at 128 cells: the middles of new edges sagged twice that before
    // they were probed.
    Simplified t = simplify_text("torus(1, 0.25);", 128, 0.1f);
    check_closed_manifold(t.m);
    CHECK(t.m.triangles.size() * 10 < t.st.unsimplified_triangles);
    CHECK(max_centroid_distance(t.m, t.c->cs) <= t.tol);
}

TEST_CASE("simplify: a box becomes its 12 triangles, corners exact", "[mesh]") {
    Simplified b = simplify_text("box([2, 1.5, 1]);", 33, 0.1f);
    check_closed_manifold(b.m);
    CHECK(b.m.triangles.size() == 12);
    CHECK(b.m.positions.size() == 8);
    CHECK(volume(b.m) == Approx(3.0).epsilon(0.001));
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 corner((k & 1) ? 1.0f : -1.0f, (k & 2) ? 0.75f : -0.75f, (k & 4) ? 0.5f : -0.5f);
        INFO("corner " << k);
        CHECK(nearest_vertex(b.m, corner) <= b.cell / 20.0f);
    }
}

TEST_CASE("simplify: a difference keeps its inner corner, a rotated box its corners", "[mesh]") {
    Simplified d = simplify_text("difference { box([2, 2, 2]); translate([1, 1, 1]) box([2, 2, 2]); }", 31, 0.1f);
    check_closed_manifold(d.m);
    CHECK(euler(d.m) == 2);
    CHECK(d.m.triangles.size() < 100);
    CHECK(volume(d.m) == Approx(7.0).epsilon(0.001));
    CHECK(nearest_vertex(d.m, {0, 0, 0}) <= d.cell / 20.0f);
    CHECK(nearest_vertex(d.m, {-1, -1, -1}) <= d.cell / 20.0f);
    Simplified r = simplify_text("rotate(x = 30, y = 20, z = 10) box([1, 1, 1]);", 40, 0.1f);
    check_closed_manifold(r.m);
    CHECK(euler(r.m) == 2);
    CHECK(r.m.triangles.size() * 20 < r.st.unsimplified_triangles);
    CHECK(max_vertex_distance(r.m, r.c->cs) <= r.tol);
    CHECK(volume(r.m) == Approx(1.0).epsilon(0.005));
}

TEST_CASE("simplify: a torus keeps its hole, CSG its parts", "[mesh]") {
    Simplified t = simplify_text("torus(1, 0.35);", 48, 0.25f);
    check_closed_manifold(t.m);
    CHECK(euler(t.m) == 0);
    CHECK(t.m.triangles.size() * 10 < t.st.unsimplified_triangles);
    CHECK(max_vertex_distance(t.m, t.c->cs) <= t.tol);
    CHECK(max_centroid_distance(t.m, t.c->cs) <= t.tol);
    CHECK(volume(t.m) == Approx(2.0 * kPi * kPi * 1.0 * 0.35 * 0.35).epsilon(0.02));
    Simplified u = simplify_text("union { sphere(1); translate([3, 0, 0]) sphere(1); }", 40, 0.25f);
    check_closed_manifold(u.m);
    CHECK(euler(u.m) == 4);
    Simplified s = simplify_text("smooth_union(0.3) { sphere(1); translate([1.5, 0, 0]) sphere(1); box([0.5, 3, 0.5]); }", 40, 0.25f);
    check_closed_manifold(s.m);
    CHECK(euler(s.m) == 2);
    CHECK(max_vertex_distance(s.m, s.c->cs) <= s.tol);
}

TEST_CASE("simplify: a thin plate and a gyroid ball stay closed and manifold", "[mesh]") {
    Simplified p = simplify_text("box([2, 0.1, 2]);", 24, 0.2f);
    check_closed_manifold(p.m);
    CHECK(euler(p.m) == 2);
    CHECK(p.m.triangles.size() < 200);
    Simplified g = simplify_text("intersection { gyroid(0.8, 0.08); sphere(1.5); }", 40, 0.25f);
    check_closed_manifold(g.m);
    CHECK(euler(g.m) == euler(mesh::mesh_scene(g.c->cs, [&] {
              mesh::MeshOptions o;
              mesh::default_box(g.c->cs, o.lo, o.hi);
              o.resolution = 40;
              return o;
          }())));
    CHECK(g.m.triangles.size() * 5 < g.st.unsimplified_triangles * 2);
    CHECK(max_vertex_distance(g.m, g.c->cs) <= g.tol * 1.1f);  // a sine field: |f| / |grad f| is the distance
}

TEST_CASE("simplify: no two triangles of small simplified meshes intersect", "[mesh]") {
    for (const char* src : {"sphere(1);", "rotate(x = 30, y = 20, z = 10) box([1, 1, 1]);",
                            "difference { box([2, 2, 2]); translate([1, 1, 1]) box([2, 2, 2]); }",
                            "smooth_union(0.3) { sphere(1); translate([1.2, 0, 0]) sphere(0.8); }", "torus(1, 0.35);",
                            "box([2, 0.1, 2]);"}) {
        INFO(src);
        Simplified m = simplify_text(src, 24, 0.5f);
        check_closed_manifold(m.m);
        CHECK(intersecting_pairs(m.m) == 0);
    }
}

TEST_CASE("simplify: colours are made for the vertices that stay", "[mesh]") {
    Simplified s = simplify_text("union { material(color = [1, 0, 0]) sphere(1); material(color = [0, 0, 1]) translate([3, 0, 0]) sphere(1); }", 32,
                                 0.25f, true);
    REQUIRE(s.m.colors.size() == s.m.positions.size());
    for (size_t i = 0; i < s.m.positions.size(); ++i) {
        const glm::vec3 want = s.m.positions[i].x < 1.5f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
        CHECK(glm::length(s.m.colors[i] - want) < 1e-3f);
    }
}

TEST_CASE("simplify: a field that refuses every move leaves the mesh as it was", "[mesh]") {
    auto c = compile_text("sphere(1);");
    mesh::MeshOptions o;
    o.resolution = 16;
    const mesh::Mesh before = mesh::mesh_scene(c->cs, o);
    mesh::Mesh m = before;
    mesh::SimplifyStats st;
    mesh::simplify_mesh(
        m, 0.1f,
        [](const glm::vec3*, size_t n, Dual* out) {
            for (size_t i = 0; i < n; ++i) out[i] = Dual{1.0f, 1.0f, 0.0f, 0.0f};  // everywhere 1 off the surface
        },
        &st);
    CHECK(st.collapses == 0);
    CHECK(st.refused_by_field > 0);
    CHECK(m.triangles.size() == before.triangles.size());
    CHECK(m.positions == before.positions);
    CHECK(bad_edges(m) == 0);
}
