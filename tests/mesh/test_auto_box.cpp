// The box a mesh is made in when none is given (runtime/mesh/auto_box.cpp): the shapes'
// bounds, or the intervals' for a custom field, floors left out; none for what is unbounded.
#include <catch2/catch.hpp>

#include <set>
#include <vector>

#include "mesh_checks.hpp"
#include "support.hpp"

using namespace sdfc;
using namespace sdfc::test;

namespace {

struct Box {
    bool found = false;
    glm::vec3 lo{0.0f}, hi{0.0f};
};

Box box_of(const std::string& src) {
    auto c = compile_text(src);
    Box b;
    b.found = mesh::default_box(c->cs, b.lo, b.hi);
    return b;
}

// lo..hi holds want_lo..want_hi with at most `slack` to spare on each side.
void check_holds(const Box& b, glm::vec3 want_lo, glm::vec3 want_hi, float slack) {
    REQUIRE(b.found);
    INFO("box " << b.lo.x << " " << b.lo.y << " " << b.lo.z << " .. " << b.hi.x << " " << b.hi.y << " " << b.hi.z);
    CHECK(glm::all(glm::lessThanEqual(b.lo, want_lo)));
    CHECK(glm::all(glm::greaterThanEqual(b.hi, want_hi)));
    CHECK(glm::all(glm::greaterThanEqual(b.lo, want_lo - slack)));
    CHECK(glm::all(glm::lessThanEqual(b.hi, want_hi + slack)));
}

}  // namespace

TEST_CASE("auto box: a custom field's box comes from the intervals", "[mesh]") {
    check_holds(box_of("field (p) -> length(p - [3, 0, 0]) - 1;"), {2, -1, -1}, {4, 1, 1}, 0.25f);
    // A smooth blend of custom fields, whose plain intervals are weak far away.
    check_holds(box_of("smooth_union(0.3) { field (p) -> length(p) - 1; translate([2, 0, 0]) field (p) -> length(p) - 0.5; }"),
                {-1, -1, -1}, {2.5f, 1, 1}, 0.35f);
}

TEST_CASE("auto box: floors are left out of a custom field scene's box, then cut into a base", "[mesh]") {
    const std::string src = "plane([0, 1, 0], -1); field (p) -> length(p) - 0.5;";
    const Box b = box_of(src);
    check_holds(b, {-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}, 0.15f);
    auto c = compile_text(src);
    mesh::MeshOptions o;
    REQUIRE(mesh::default_box(c->cs, o.lo, o.hi));
    o.resolution = 24;
    const mesh::Mesh m = mesh::mesh_scene(c->cs, o);
    CHECK(bad_edges(m) == 0);
    CHECK(euler(m) == 2);  // the ball (the floor, at y = -1, is outside the box)
}

TEST_CASE("auto box: unbounded scenes have none", "[mesh]") {
    CHECK_FALSE(box_of("plane([0, 1, 0], 0);").found);
    CHECK_FALSE(box_of("field (p) -> p.y;").found);
    CHECK_FALSE(box_of("repeat([2, 2, 2]) sphere(0.5);").found);
    CHECK_FALSE(box_of("field (p) -> 1;").found);  // no surface anywhere
}

TEST_CASE("auto box: a part of a micrometre gets a margin of its own size", "[mesh]") {
    check_holds(box_of("sphere(1e-6);"), glm::vec3(-1e-6f), glm::vec3(1e-6f), 1e-7f);
}

TEST_CASE("auto box: shapes apart intersected (nothing anywhere) get [-1, 1]^3, where the mesh is empty", "[mesh]") {
    const Box b = box_of("intersection { translate([-2, 0, 0]) sphere(1); translate([2, 0, 0]) sphere(1); }");
    check_holds(b, glm::vec3(-1.0f), glm::vec3(1.0f), 0.05f);  // (with the usual margin)
}

TEST_CASE("auto box: a floor moved or turned by constants is a floor too", "[mesh]") {
    // The box of the rest, as for plane(offset = -0.6): translate and rotate place the plane.
    const Box plain = box_of("sphere(1); plane([0, 1, 0], -0.6);");
    REQUIRE(plain.found);
    for (const char* src : {"sphere(1); translate([0, -0.6, 0]) plane();", "sphere(1); translate([5, -0.6, 2]) material(color = [1, 0, 0]) plane();",
                            "sphere(1); rotate(x = 20) translate([0, -2, 0]) plane();"}) {
        INFO(src);
        const Box b = box_of(src);
        REQUIRE(b.found);
        CHECK(glm::all(glm::lessThanEqual(b.lo, glm::vec3(-1.0f))));
        CHECK(glm::all(glm::greaterThanEqual(b.hi, glm::vec3(1.0f))));
    }
    auto c = compile_text("sphere(1); rotate(x = 20) translate([0, -2, 0]) plane();");
    REQUIRE(c->cs.half_spaces.size() == 1);
    const glm::vec4 h = c->cs.half_spaces[0];  // the plane's normal turned by 20 degrees about x
    CHECK(h.x == Approx(0.0f).margin(1e-6));
    CHECK(h.y == Approx(std::cos(glm::radians(20.0f))));
    CHECK(h.z == Approx(std::sin(glm::radians(20.0f))));
    CHECK(h.w == Approx(-2.0f));
    auto m = compile_text("sphere(1); translate([0, -0.6, 0]) plane();");
    REQUIRE(m->cs.half_spaces.size() == 1);
    CHECK(m->cs.half_spaces[0].w == Approx(-0.6f));
    // A uniform scale (a model in inches: scale(25.4) { ... }) scales the floor's offset.
    auto s = compile_text("scale(2) { sphere(0.5); translate([0, -0.3, 0]) plane(); }");
    REQUIRE(s->cs.half_spaces.size() == 1);
    CHECK(s->cs.half_spaces[0].y == Approx(1.0f));
    CHECK(s->cs.half_spaces[0].w == Approx(-0.6f));
    CHECK(box_of("scale(2) { sphere(0.5); plane(offset = -0.3); }").found);
    CHECK(compile_text("scale([1, 2, 1]) { sphere(0.5); plane(); }")->cs.half_spaces.empty());  // not a plane's scale
    // A floor blended into the rest: the half-space and the box grown by the blend's radius.
    auto b = compile_text("smooth_union(0.3) { sphere(1); plane(offset = -1.2); }");
    REQUIRE(b->cs.half_spaces.size() == 1);
    CHECK(b->cs.half_spaces[0].w == Approx(-0.9f));
    const Box blended = box_of("smooth_union(0.3) { sphere(1); plane(offset = -1.2); }");
    REQUIRE(blended.found);
    CHECK(blended.hi.x >= 1.3f);
}

namespace {
// The scene meshed in its default box at `res` cells across; the box in o.
mesh::Mesh mesh_in_default_box(const CompiledScene& cs, int res, mesh::MeshOptions& o) {
    o.resolution = res;
    REQUIRE(mesh::default_box(cs, o.lo, o.hi, 0.0f, 8192, res));
    return mesh::mesh_scene(cs, o);
}
}  // namespace

TEST_CASE("auto box: a floor at the rest's bounds is a base at a coarse resolution too", "[mesh]") {
    // The base is the margin below the sphere: at 32 cells, 2 % of the box is under a cell.
    auto c = compile_text("sphere(1); translate([0, -1, 0]) plane();");
    for (int res : {16, 32, 48}) {
        INFO("resolution " << res);
        mesh::MeshOptions o;
        const mesh::Mesh m = mesh_in_default_box(c->cs, res, o);
        float x0 = INFINITY, x1 = -INFINITY;
        for (const glm::vec3& p : m.positions) x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
        CHECK(x0 == Approx(o.lo.x));  // the base reaches the box's sides
        CHECK(x1 == Approx(o.hi.x));
        CHECK(bad_edges(m) == 0);
    }
}

TEST_CASE("mesh: solids that touch on a grid plane are one piece (a box on a floor, two boxes side by side)", "[mesh]") {
    // The samples on the plane between them read 0: they join the solids, not part them.
    auto pieces = [](const mesh::Mesh& m) {
        std::vector<uint32_t> up(m.positions.size());
        for (uint32_t i = 0; i < up.size(); ++i) up[i] = i;
        auto root = [&](uint32_t x) {
            while (up[x] != x) x = up[x] = up[up[x]];
            return x;
        };
        for (const auto& t : m.triangles) up[root(t[0])] = root(t[1]), up[root(t[1])] = root(t[2]);
        std::set<uint32_t> roots;
        for (const auto& t : m.triangles) roots.insert(root(t[0]));
        return roots.size();
    };
    auto floor = compile_text("translate([0, 1, 0]) box(2); plane();");
    for (int res : {20, 32, 64}) {
        INFO("resolution " << res);
        mesh::MeshOptions o;
        const mesh::Mesh m = mesh_in_default_box(floor->cs, res, o);
        CHECK(pieces(m) == 1);
        CHECK(bad_edges(m) == 0);
    }
    auto bar = compile_text("box(1); translate([1, 0, 0]) box(1);");
    mesh::MeshOptions o;
    o.lo = glm::vec3(-0.75f, -0.75f, -0.75f), o.hi = glm::vec3(1.75f, 0.75f, 0.75f);
    o.resolution = 20;  // cells of 0.125: x = 0.5 is a grid plane
    const mesh::Mesh m = mesh::mesh_scene(bar->cs, o);
    CHECK(pieces(m) == 1);
    CHECK(volume(m) == Approx(2.0).epsilon(0.01));
}
