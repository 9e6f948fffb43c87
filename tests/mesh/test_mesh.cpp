// Dual contouring (runtime/mesh): closed, oriented, manifold meshes of the right volume
// and topology, vertices on the surface, corners and edges kept sharp, and the files read
// back.
#include <catch2/catch.hpp>

#include <array>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "mesh_checks.hpp"
#include "runtime/mesh/cube.hpp"
#include "runtime/mesh/mesh_3mf.hpp"
#include "runtime/mesh/mesh_file.hpp"
#include "support.hpp"

using namespace sdfc;
using namespace sdfc::test;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Meshed {
    std::unique_ptr<Compiled> c;
    mesh::Mesh m;
    float cell = 0.0f;
};

Meshed mesh_text(const std::string& src, int resolution) {
    Meshed r;
    r.c = compile_text(src);
    mesh::MeshOptions o;
    REQUIRE(mesh::default_box(r.c->cs, o.lo, o.hi));
    o.resolution = resolution;
    const glm::vec3 ext = o.hi - o.lo;
    r.cell = std::max({ext.x, ext.y, ext.z}) / float(resolution);
    r.m = mesh::mesh_scene(r.c->cs, o);
    return r;
}

void check_closed_manifold(const mesh::Mesh& m) {
    REQUIRE(!m.triangles.empty());
    CHECK(bad_edges(m) == 0);
    CHECK(pinched_vertices(m) == 0);
}

}  // namespace

TEST_CASE("mesh: every cube configuration's patches are cycles the face rule makes consistent", "[mesh]") {
    for (int c = 0; c < 256; ++c)
        for (int f = 0; f < 64; ++f) {
            const mesh::Patches& p = mesh::patches(uint8_t(c), uint8_t(f));
            int crossing = 0, per_patch[4] = {0, 0, 0, 0};
            for (int e = 0; e < 12; ++e) {
                const auto k = mesh::edge_corners(e);
                const bool crosses = ((c >> k[0]) & 1) != ((c >> k[1]) & 1);
                CHECK((p.of_edge[e] >= 0) == crosses);
                if (crosses) ++crossing, ++per_patch[p.of_edge[e]];
            }
            for (int q = 0; q < p.count; ++q) CHECK(per_patch[q] >= 3);  // a patch is a polygon
            CHECK((c == 0 || c == 255) == (crossing == 0));
        }
    // The ambiguous face of two diagonal inside corners: separate by default, joined flipped.
    CHECK(mesh::patches(0b0000'1001).count == 2);
    CHECK(mesh::patches(0b0000'1001, 0b010000).count == 1);  // face 4: z = 0, holding corners 0 and 3
}

TEST_CASE("mesh: a sphere is closed, genus 0, of the right volume, its vertices on the surface", "[mesh]") {
    Meshed s = mesh_text("sphere(1);", 40);
    check_closed_manifold(s.m);
    CHECK(euler(s.m) == 2);
    CHECK(volume(s.m) == Approx(4.0 / 3.0 * kPi).epsilon(0.005));
    CHECK(max_vertex_distance(s.m, s.c->cs) <= s.cell / 20.0f);
}

TEST_CASE("mesh: a box keeps its corners and edges", "[mesh]") {
    Meshed b = mesh_text("box([2, 1.5, 1]);", 33);
    check_closed_manifold(b.m);
    CHECK(euler(b.m) == 2);
    CHECK(volume(b.m) == Approx(3.0).epsilon(0.005));
    CHECK(max_vertex_distance(b.m, b.c->cs) <= b.cell / 20.0f);
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 corner((k & 1) ? 1.0f : -1.0f, (k & 2) ? 0.75f : -0.75f, (k & 4) ? 0.5f : -0.5f);
        INFO("corner " << k);
        CHECK(nearest_vertex(b.m, corner) <= b.cell / 20.0f);
    }
    // A point on an edge, between vertices: the edge's vertices lie on it.
    size_t on_edge = 0;
    for (const glm::vec3& v : b.m.positions)
        on_edge += std::fabs(std::fabs(v.x) - 1.0f) < b.cell / 20.0f && std::fabs(std::fabs(v.y) - 0.75f) < b.cell / 20.0f;
    CHECK(on_edge >= 4 * 10);  // about 1 / cell vertices along each of the 4 edges
}

TEST_CASE("mesh: a rotated box keeps its corners, its vertices on the surface", "[mesh]") {
    // Cells cut its edges at every angle: vertices the planes leave off the surface are
    // moved onto it.
    Meshed b = mesh_text("rotate(x = 30, y = 20, z = 10) box([1, 1, 1]);", 40);
    check_closed_manifold(b.m);
    CHECK(euler(b.m) == 2);
    CHECK(volume(b.m) == Approx(1.0).epsilon(0.005));
    CHECK(max_vertex_distance(b.m, b.c->cs) <= b.cell / 20.0f);
    // The 8 corners, sqrt(3)/2 from the centre. A corner whose cell holds crossings of all
    // three of its faces gets a vertex on it; the others (this box at this grid: 4 of 8)
    // are cut within their cell, their edges kept.
    std::vector<glm::vec3> corners;
    for (const glm::vec3& v : b.m.positions)
        if (std::fabs(glm::length(v) - 0.8660254f) < b.cell / 20.0f) {
            bool seen = false;
            for (const glm::vec3& c : corners) seen |= glm::length(c - v) < 0.5f;
            if (!seen) corners.push_back(v);
        }
    CHECK(corners.size() >= 4);
    float farthest = 0.0f;
    for (const glm::vec3& v : b.m.positions) farthest = std::max(farthest, glm::length(v));
    CHECK(farthest <= 0.8660254f + b.cell / 20.0f);
}

TEST_CASE("mesh: a difference keeps its inner corners", "[mesh]") {
    // A unit cube with the octant x, y, z > 0 cut away: an inner corner at the origin.
    Meshed d = mesh_text("difference { box([2, 2, 2]); translate([1, 1, 1]) box([2, 2, 2]); }", 31);
    check_closed_manifold(d.m);
    CHECK(euler(d.m) == 2);
    CHECK(volume(d.m) == Approx(7.0).epsilon(0.005));
    CHECK(nearest_vertex(d.m, {0, 0, 0}) <= d.cell / 20.0f);
    CHECK(nearest_vertex(d.m, {-1, -1, -1}) <= d.cell / 20.0f);
    CHECK(nearest_vertex(d.m, {1, 0, 0}) <= d.cell / 20.0f);
}

TEST_CASE("mesh: edges and faces on grid planes give no two vertices one position (STL has no indices)", "[mesh]") {
    // The hexagon's corners at x = +-0.5 and the slab's faces lie on planes of the grid.
    const auto c = compile_text("difference { box([4, 1, 4]); rotate(y = 30) hex_prism(3, 0.5); }\n"
                                "translate([0, 1.5, 0]) box([2, 1, 2]);\n");
    mesh::MeshOptions o;
    o.lo = glm::vec3(-1, -2, -1), o.hi = glm::vec3(1, 2, 1);
    o.resolution = 40;
    const mesh::Mesh m = mesh::mesh_scene(c->cs, o);
    check_closed_manifold(m);
    std::set<std::array<float, 3>> at;
    for (const glm::vec3& v : m.positions) at.insert({v.x, v.y, v.z});
    CHECK(at.size() == m.positions.size());
    size_t flat = 0;
    for (const auto& t : m.triangles)
        flat += glm::length(glm::cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]])) == 0.0f;
    CHECK(flat == 0);
    // The walls of the box meshed stay where they are.
    float x0 = INFINITY, x1 = -INFINITY;
    for (const glm::vec3& v : m.positions) x0 = std::min(x0, v.x), x1 = std::max(x1, v.x);
    CHECK(x0 == -1.0f);
    CHECK(x1 == 1.0f);
}

TEST_CASE("mesh: a torus has genus 1", "[mesh]") {
    Meshed t = mesh_text("torus(1, 0.35);", 48);
    check_closed_manifold(t.m);
    CHECK(euler(t.m) == 0);
    CHECK(volume(t.m) == Approx(2.0 * kPi * kPi * 1.0 * 0.35 * 0.35).epsilon(0.005));
    CHECK(max_vertex_distance(t.m, t.c->cs) <= t.cell / 20.0f);
}

TEST_CASE("mesh: CSG and smooth CSG stay closed", "[mesh]") {
    Meshed u = mesh_text("union { sphere(1); translate([3, 0, 0]) sphere(1); }", 40);
    check_closed_manifold(u.m);
    CHECK(euler(u.m) == 4);  // two spheres
    CHECK(volume(u.m) == Approx(8.0 / 3.0 * kPi).epsilon(0.005));
    Meshed s = mesh_text("smooth_union(0.3) { sphere(1); translate([1.5, 0, 0]) sphere(1); box([0.5, 3, 0.5]); }", 40);
    check_closed_manifold(s.m);
    CHECK(euler(s.m) == 2);
    Meshed i = mesh_text("intersection { box([2, 2, 2]); sphere(1.3); }", 37);
    check_closed_manifold(i.m);
    CHECK(euler(i.m) == 2);
}

TEST_CASE("mesh: a plate thinner than a cell and a gyroid ball stay closed and manifold", "[mesh]") {
    // Both faces of the plate in the same layer of cells: cells with two patches.
    Meshed p = mesh_text("box([2, 0.1, 2]);", 24);
    check_closed_manifold(p.m);
    CHECK(euler(p.m) == 2);
    Meshed q = mesh_text("rotate(x = 30, z = 20) box([2, 0.07, 2]);", 24);
    check_closed_manifold(q.m);
    Meshed g = mesh_text("intersection { gyroid(0.8, 0.08); sphere(1.5); }", 60);
    check_closed_manifold(g.m);
    Meshed r = mesh_text("intersection { gyroid(0.8, 0.08); sphere(1.5); }", 23);  // thin walls at a coarse grid
    check_closed_manifold(r.m);
}

TEST_CASE("mesh: a cell's two sheets keep two positions (an STL reader merges equal ones)", "[mesh]") {
    // examples/gyroid-ball.sdf's field at 48 and 64 cells: 6 and 12 such pairs met at one point.
    for (const int res : {48, 64}) {
        INFO(res);
        Meshed g = mesh_text("intersection { sphere(1); gyroid(0.5, 0.05); }", res);
        check_closed_manifold(g.m);
        std::set<std::array<float, 3>> at;
        for (const glm::vec3& v : g.m.positions) at.insert({v.x, v.y, v.z});
        CHECK(at.size() == g.m.positions.size());
    }
}

TEST_CASE("mesh: the box cuts the solid and closes it with a lid", "[mesh]") {
    auto c = compile_text("plane([0, 1, 0], 0);");
    mesh::MeshOptions o;
    o.lo = {-1, -1, -1}, o.hi = {1, 1, 1};
    o.resolution = 16;
    const mesh::Mesh m = mesh::mesh_scene(c->cs, o);
    check_closed_manifold(m);
    CHECK(euler(m) == 2);
    CHECK(volume(m) == Approx(4.0).epsilon(0.005));  // the half below y = 0
    CHECK(nearest_vertex(m, {-1, -1, -1}) <= 0.125f / 20.0f);
    CHECK(nearest_vertex(m, {1, 0, 1}) <= 0.125f / 20.0f);
}

TEST_CASE("mesh: no two triangles of small meshes intersect", "[mesh]") {
    for (const char* src : {"sphere(1);", "box([2, 1.5, 1]);", "rotate(x = 30, y = 20, z = 10) box([1, 1, 1]);", "difference { box([2, 2, 2]); translate([1, 1, 1]) box([2, 2, 2]); }",
                            "smooth_union(0.3) { sphere(1); translate([1.2, 0, 0]) sphere(0.8); }", "torus(1, 0.35);"}) {
        INFO(src);
        Meshed m = mesh_text(src, 14);
        CHECK(intersecting_pairs(m.m) == 0);
    }
}

TEST_CASE("mesh: the limit on triangles is an error, not memory", "[mesh]") {
    auto c = compile_text("sphere(1);");
    mesh::MeshOptions o;
    o.resolution = 64;
    o.max_triangles = 1000;
    CHECK_THROWS_WITH(mesh::mesh_scene(c->cs, o), Catch::Matchers::Contains("over the limit of 1000 (raise it with --max-triangles)"));
}

TEST_CASE("mesh: STL, OBJ, PLY and 3MF encode what they should", "[mesh]") {
    Meshed s = mesh_text("material(color = [1, 0.5, 0]) box([1, 1, 1]);", 6);
    s.m.colors.assign(s.m.positions.size(), glm::vec3(1.0f, 0.5f, 0.0f));
    const std::string stl = mesh::encode_mesh(s.m, mesh::MeshFormat::Stl);
    uint32_t n = 0;
    std::memcpy(&n, stl.data() + 80, 4);
    CHECK(n == s.m.triangles.size());
    CHECK(stl.size() == 84 + 50 * size_t(n));
    float first[12];
    std::memcpy(first, stl.data() + 84, sizeof first);
    const glm::vec3 a = s.m.positions[s.m.triangles[0][0]];
    CHECK(first[3] == a.x);
    CHECK(first[4] == a.y);
    CHECK(first[5] == a.z);
    // OBJ: the vertices and faces read back, 1-based, with the colour extension.
    std::istringstream obj(mesh::encode_mesh(s.m, mesh::MeshFormat::Obj));
    size_t v = 0, f = 0;
    for (std::string line; std::getline(obj, line);) {
        if (line.rfind("v ", 0) == 0) {
            float x, y, z, r, g, b;
            REQUIRE(std::sscanf(line.c_str(), "v %f %f %f %f %f %f", &x, &y, &z, &r, &g, &b) == 6);
            CHECK(x == s.m.positions[v].x);
            CHECK(g == Approx(0.7354f).margin(1e-3));  // linear 0.5 in sRGB, as the renderer shows it
            ++v;
        } else if (line.rfind("f ", 0) == 0) {
            unsigned i, j, k;
            REQUIRE(std::sscanf(line.c_str(), "f %u %u %u", &i, &j, &k) == 3);
            CHECK(i == s.m.triangles[f][0] + 1);
            ++f;
        }
    }
    CHECK(v == s.m.positions.size());
    CHECK(f == s.m.triangles.size());
    const std::string ply = mesh::encode_mesh(s.m, mesh::MeshFormat::Ply);
    const size_t body = ply.find("end_header\n") + 11;
    CHECK(ply.find("property uchar red") != std::string::npos);
    CHECK(ply.size() == body + 15 * s.m.positions.size() + 13 * s.m.triangles.size());
    CHECK(uint8_t(ply[body + 13]) == 188);  // green of the first vertex: linear 0.5 -> sRGB 188
    // 3MF, read back through lib3mf: the same vertices and triangles.
    const mesh::Mesh back = mesh::decode_3mf(mesh::encode_mesh(s.m, mesh::MeshFormat::ThreeMf));
    REQUIRE(back.positions.size() == s.m.positions.size());
    float worst = 0.0f;  // 3MF keeps coordinates as decimal text
    for (size_t i = 0; i < back.positions.size(); ++i) worst = std::max(worst, glm::length(back.positions[i] - s.m.positions[i]));
    CHECK(worst < 1e-5f);
    CHECK(back.triangles == s.m.triangles);
    // An empty mesh (a warning in sdfc mesh) is written in every format, 3MF too.
    for (const auto f : {mesh::MeshFormat::Stl, mesh::MeshFormat::Obj, mesh::MeshFormat::Ply, mesh::MeshFormat::ThreeMf})
        CHECK_NOTHROW(mesh::encode_mesh(mesh::Mesh{}, f));
    CHECK(mesh::decode_3mf(mesh::encode_mesh(mesh::Mesh{}, mesh::MeshFormat::ThreeMf)).triangles.empty());
    CHECK(mesh::mesh_format("x.3MF") == mesh::MeshFormat::ThreeMf);
    CHECK(mesh::mesh_format("a/b.STL") == mesh::MeshFormat::Stl);
    CHECK(mesh::mesh_format("b.png") == mesh::MeshFormat::Unknown);
}

TEST_CASE("mesh: the scene's colours reach the vertices", "[mesh]") {
    auto c = compile_text("material(color = [1, 0, 0]) sphere(1); material(color = [0, 0, 1]) translate([3, 0, 0]) sphere(1);");
    mesh::MeshOptions o;
    REQUIRE(mesh::default_box(c->cs, o.lo, o.hi));
    o.resolution = 24;
    o.colors = true;
    const mesh::Mesh m = mesh::mesh_scene(c->cs, o);
    REQUIRE(m.colors.size() == m.positions.size());
    for (size_t i = 0; i < m.positions.size(); ++i) {
        const glm::vec3 want = m.positions[i].x < 1.5f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
        CHECK(glm::length(m.colors[i] - want) < 1e-5f);
    }
}
