// Renderer tests: small scenes built by hand (IR Graph -> codegen -> Program), checked by
// pixels. Also the camera and image files (round trips, atomic replace).
#include <catch2/catch.hpp>
#include "support.hpp"

#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>

#include "compiler/bytecode/compile.hpp"
#include "compiler/render/camera.hpp"
#include "runtime/io/image.hpp"
#include "runtime/cpu/slice.hpp"
#include "runtime/cpu/tracer.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

namespace {

// A scene under construction: the graph, the point inputs and shape/material helpers.
struct Builder {
    Graph g;
    NodeId x, y, z;
    Builder() : x(g.input(Op::VarX)), y(g.input(Op::VarY)), z(g.input(Op::VarZ)) {}

    NodeId c(float v) { return g.constant(v); }
    NodeId sphere(glm::vec3 at, float r) {
        return g.sub(g.ternary(Op::Length3, g.addc(x, -at.x), g.addc(y, -at.y), g.addc(z, -at.z)), c(r));
    }
    NodeId floor(float h) { return g.addc(y, -h); }  // solid below y = h
    MaterialN material(glm::vec3 color, float reflect = 0, float transparency = 0, glm::vec3 emit = {0, 0, 0},
                       float specular = 0.0f, float ior = 1.5f) {
        MaterialN m;
        m[kMatR] = c(color.r), m[kMatG] = c(color.g), m[kMatB] = c(color.b);
        m[kMatSpecular] = c(specular), m[kMatShininess] = c(32);
        m[kMatReflect] = c(reflect), m[kMatTransparency] = c(transparency), m[kMatIor] = c(ior);
        m[kMatEmitR] = c(emit.r), m[kMatEmitG] = c(emit.g), m[kMatEmitB] = c(emit.b);
        return m;
    }
    // Union of two shapes with the nearer one's material.
    std::pair<NodeId, MaterialN> unite(NodeId da, const MaterialN& ma, NodeId db, const MaterialN& mb) {
        NodeId closer = g.binary(Op::Lt, da, db);
        MaterialN m;
        for (int i = 0; i < kMatChannels; ++i) m[i] = g.select(closer, ma[i], mb[i]);
        return {g.min(da, db), m};
    }

    CompiledScene compile(NodeId d, const MaterialN& m, int w = 64, int h = 48) {
        CompiledScene s;
        s.distance = codegen(g, {d}, {"d"});
        std::vector<NodeId> roots{d};
        std::vector<std::string> names{"d"};
        for (int i = 0; i < kMatChannels; ++i) roots.push_back(m[i]), names.push_back("m" + std::to_string(i));
        s.shading = codegen(g, roots, names);
        s.render.width = w;
        s.render.height = h;
        s.lights = {ResolvedLight{}};
        s.lights[0].position = {3, 4, 6};
        s.lights[0].intensity = 60;
        s.ambient = glm::vec3(0.05f);
        s.background = glm::vec3(0.1f, 0.2f, 0.3f);
        return s;
    }
};

glm::vec3 px(const Image& img, int x, int y) { return {img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2)}; }
glm::vec3 px(const Image& img, glm::vec2 p) { return px(img, static_cast<int>(p.x), static_cast<int>(p.y)); }
float lum(glm::vec3 c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

glm::vec2 project(const CompiledScene& s, glm::vec3 p) {
    return Camera(s.camera, s.render.width, s.render.height).project(p);
}

// A fresh, empty folder for file tests.
fs::path temp_dir(const std::string& name) {
    fs::path d = fs::temp_directory_path() / ("sdfc-test-" + std::to_string(::getpid()) + "-" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

// The default test scene: a red sphere of radius 1 at the origin, seen from +z.
CompiledScene red_sphere(Builder& b, int w = 64, int h = 48) {
    CompiledScene s = b.compile(b.sphere({0, 0, 0}, 1), b.material({1.0f, 0.1f, 0.1f}), w, h);
    s.camera.position = {0, 0, 5};
    s.camera.target = {0, 0, 0};
    return s;
}

// Plane y = 0 with a sphere (r 0.5) resting on it, a steep light from +x, camera looking
// straight down (orthographic, 4 units tall, +x to the right). The sphere's shadow centre
// lies at x = 1 for the directional light below.
CompiledScene shadow_scene(Builder& b, float radius, bool point_light = false) {
    auto [d, m] = b.unite(b.sphere({0, 0.5f, 0}, 0.5f), b.material({0.8f, 0.8f, 0.8f}), b.floor(0), b.material({0.8f, 0.8f, 0.8f}));
    CompiledScene s = b.compile(d, m, 64, 64);
    s.camera.position = {0.25f, 5, 0};
    s.camera.target = {0.25f, 0, 0};
    s.camera.up = {0, 0, -1};
    s.camera.orthographic = true;
    s.camera.ortho_height = 4;
    s.lights[0] = ResolvedLight{};
    if (point_light) {
        s.lights[0].position = glm::vec3(0, 0.5f, 0) + glm::normalize(glm::vec3(-2, 1, 0)) * 6.0f;
        s.lights[0].intensity = 36;
    } else {
        s.lights[0].directional = true;
        s.lights[0].direction = glm::normalize(glm::vec3(2, -1, 0));
        s.lights[0].intensity = 1;
    }
    s.lights[0].radius = radius;
    s.render.ao = false;
    return s;
}

}  // namespace

TEST_CASE("camera: rays through the centre, the top row and orthographic", "[camera]") {
    ResolvedCamera rc;
    rc.position = {0, 0, 5};
    rc.target = {0, 0, 0};
    rc.fov = 90;
    Camera cam(rc, 100, 50);
    Ray r = cam.ray(50, 25);
    CHECK(r.dir.z == Approx(-1).margin(1e-6));
    CHECK(glm::length(r.dir) == Approx(1));
    // Row 0 is the top: its rays point up. Column 0 is the left.
    CHECK(cam.ray(50, 0.5f).dir.y > 0.3f);
    CHECK(cam.ray(0.5f, 25).dir.x < -0.3f);
    // fov 90: the top edge is 45 degrees up.
    Ray top = cam.ray(50, 0);
    CHECK(top.dir.y / -top.dir.z == Approx(1).epsilon(1e-5));
    glm::vec2 back = cam.project({0.3f, -0.2f, 1});
    Ray through = cam.ray(back.x, back.y);
    CHECK(glm::length(glm::normalize(glm::vec3(0.3f, -0.2f, 1) - rc.position) - through.dir) < 1e-5f);

    rc.orthographic = true;
    rc.ortho_height = 4;
    Camera ortho(rc, 100, 50);
    Ray a = ortho.ray(0, 0), b = ortho.ray(100, 50);
    CHECK(a.dir == b.dir);
    CHECK(a.origin.y == Approx(2));
    CHECK(b.origin.x == Approx(4));  // aspect 2: 8 units wide

    // Degenerate: up parallel to the view direction still gives finite rays.
    rc.orthographic = false;
    rc.position = {0, 5, 0};
    rc.up = {0, 1, 0};
    Camera down(rc, 10, 10);
    Ray dn = down.ray(3, 3);
    CHECK(std::isfinite(dn.dir.x));
    CHECK(std::isfinite(dn.dir.z));
}

TEST_CASE("render: a lit red sphere on the background", "[render]") {
    Builder b;
    CompiledScene s = red_sphere(b);
    Image img = render(s, {});
    REQUIRE(img.width == 64);
    REQUIRE(img.height == 48);
    REQUIRE(img.pixels.size() == 64u * 48u * 3u);
    glm::vec3 centre = px(img, 32, 24);
    CHECK(centre.r > 0.3f);
    CHECK(centre.r > 4.0f * centre.g);
    CHECK(centre.g == Approx(centre.b).margin(1e-4));
    for (auto [x, y] : {std::pair{0, 0}, {63, 0}, {0, 47}, {63, 47}}) {
        glm::vec3 c = px(img, x, y);
        CHECK(c.r == s.background.r);
        CHECK(c.g == s.background.g);
        CHECK(c.b == s.background.b);
    }
    // The lit side (light at +x +y) is brighter than the opposite side.
    glm::vec2 lit = project(s, glm::normalize(glm::vec3(0.5f, 0.5f, 1)));
    glm::vec2 dark = project(s, glm::normalize(glm::vec3(-0.6f, -0.6f, 0.5f)));
    CHECK(px(img, lit).r > 2.0f * px(img, dark).r);
}

TEST_CASE("render: bounds do not change the picture", "[render]") {
    Builder b;
    CompiledScene s = red_sphere(b);
    Image a = render(s, {});
    s.bounds.lo = glm::vec3(-1);
    s.bounds.hi = glm::vec3(1);
    Image c = render(s, {});
    size_t differ = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) differ += std::fabs(a.pixels[i] - c.pixels[i]) > 1e-3f;
    CHECK(differ <= 6);
    CHECK(px(c, 0, 0) == s.background);
}

TEST_CASE("render: a sphere casts a hard shadow on a plane", "[render][shadow]") {
    Builder b;
    CompiledScene s = shadow_scene(b, 0.0f);
    Image img = render(s, {});
    glm::vec3 shadow = px(img, project(s, {1.0f, 0, 0}));
    glm::vec3 lit = px(img, project(s, {-1.5f, 0, 0}));
    CHECK(lum(lit) > 0.2f);
    CHECK(lum(shadow) < 0.3f * lum(lit));
    // In full shadow only the ambient term is left.
    CHECK(shadow.r == Approx(0.8f * 0.05f).epsilon(1e-3));

    s.render.shadows = false;
    Image noshadow = render(s, {});
    CHECK(lum(px(noshadow, project(s, {1.0f, 0, 0}))) > 0.8f * lum(lit));
}

TEST_CASE("render: identical pixels for any thread count", "[render][determinism]") {
    Builder b;
    auto [d, m] = b.unite(b.sphere({0, 0, 0}, 1), b.material({0.9f, 0.3f, 0.2f}, 0.3f), b.floor(-1),
                          b.material({0.5f, 0.5f, 0.5f}, 0.0f, 0.0f, {0, 0, 0}, 0.5f));
    CompiledScene s = b.compile(d, m, 96, 64);
    s.camera.position = {0, 1, 5};
    s.lights[0].radius = 0.3f;
    for (std::string aa : {"grid", "cone"}) {
        s.render.aa = aa;
        s.render.samples = aa == "grid" ? 3 : 1;
        RenderOptions o1, o2, o0;
        o1.threads = 1, o2.threads = 2;
        o1.aovs = o2.aovs = o0.aovs = {"depth", "normal", "steps"};
        Image a = render(s, o1), c = render(s, o2), e = render(s, o0);
        REQUIRE(a.pixels.size() == c.pixels.size());
        CHECK(std::memcmp(a.pixels.data(), c.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
        CHECK(std::memcmp(a.pixels.data(), e.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
        for (size_t k = 0; k < a.aovs.size(); ++k)
            CHECK(std::memcmp(a.aovs[k].data.data(), c.aovs[k].data.data(), a.aovs[k].data.size() * sizeof(float)) == 0);
    }
}

TEST_CASE("render: NaN in the field or the material never reaches a pixel", "[render][nan]") {
    Builder b;
    // log(x) is NaN for x < 0: the left half of space has no valid distance.
    NodeId nan_left = b.g.mulc(b.g.unary(Op::Log, b.x), 1e-3f);
    NodeId d = b.g.add(b.sphere({0, 0, 0}, 1), nan_left);
    MaterialN m = b.material({1, 1, 1}, 0.5f, 0.3f);
    m[kMatR] = b.g.unary(Op::Sqrt, b.x);       // NaN colour on the left
    m[kMatShininess] = b.g.unary(Op::Log, b.y);  // NaN shininess below
    CompiledScene s = b.compile(d, m);
    s.camera.position = {0.2f, 0.3f, 5};
    s.lights.push_back(ResolvedLight{});
    s.lights[1].radius = 0.5f;
    s.lights[1].position = {-3, -3, 3};
    for (std::string aa : {"grid", "cone"}) {
        s.render.aa = aa;
        RenderOptions o;
        o.aovs = {"depth", "normal", "steps"};
        Image img = render(s, o);
        CHECK(test::all_finite(img));
        // The right half still shows the sphere.
        CHECK(lum(px(img, project(s, {0.5f, 0, 1}))) > lum(s.background));
    }
    // A field that is NaN everywhere renders as background.
    Builder b2;
    NodeId all_nan = b2.g.unary(Op::Sqrt, b2.g.sub(b2.g.neg(b2.g.abs(b2.x)), b2.c(1)));
    CompiledScene s2 = b2.compile(all_nan, b2.material({1, 1, 1}));
    Image img2 = render(s2, {});
    CHECK(test::all_finite(img2));
    CHECK(px(img2, 32, 24) == s2.background);
}

TEST_CASE("render: AOVs depth, normal and steps", "[render][aov]") {
    Builder b;
    CompiledScene s = red_sphere(b);
    RenderOptions o;
    o.aovs = {"depth", "normal", "steps"};
    Image img = render(s, o);
    REQUIRE(img.aovs.size() == 3);
    const AovPlane* depth = img.aov("depth");
    const AovPlane* normal = img.aov("normal");
    const AovPlane* steps = img.aov("steps");
    REQUIRE(depth);
    REQUIRE(normal);
    REQUIRE(steps);
    REQUIRE(normal->channels == 3);
    const size_t c = 24 * 64 + 32, corner = 0;
    CHECK(depth->data[c] == Approx(4.0f).margin(0.01f));
    CHECK(depth->data[corner] == INFINITY);  // a miss
    CHECK(normal->data[c * 3 + 2] == Approx(1.0f).margin(0.01f));
    CHECK(normal->data[corner * 3 + 2] == 0.0f);
    CHECK(steps->data[c] >= 1.0f);
    CHECK(steps->data[c] < 64.0f);

    o.aovs = {"bogus"};
    CHECK_THROWS_AS(render(s, o), std::invalid_argument);
}

TEST_CASE("render: steps view is a heat map of the step counts", "[render][aov]") {
    Builder b;
    CompiledScene s = red_sphere(b);
    RenderOptions o;
    o.view = RenderView::Steps;
    Image img = render(s, o);
    CHECK(test::all_finite(img));
    // Misses near the silhouette take more steps than the head-on centre: hotter colour.
    glm::vec3 centre = px(img, 32, 24);
    glm::vec2 near_edge = project(s, {1.03f, 0, 0});
    CHECK(lum(px(img, near_edge)) > lum(centre));
    CHECK(px(img, 32, 24) != px(render(s, {}), 32, 24));
}

TEST_CASE("render: raw fields (no distance bound) are marched by sign", "[render][raw]") {
    Builder b;
    // Ten times a sphere's distance: sphere tracing would step 10x too far and miss.
    NodeId f = b.g.mulc(b.sphere({0, 0, 0}, 1), 10.0f);
    // Plus a sheet where the field comes within 1e-5 of zero without crossing it (at z = 0.5,
    // away from the sphere): not a surface.
    NodeId sheet = b.g.addc(b.g.abs(b.g.addc(b.z, -0.5f)), 1e-5f);
    CompiledScene s = red_sphere(b);
    s.distance = codegen(b.g, {f}, {"d"});
    Image traced = render(s, {});
    CHECK(px(traced, 32, 24) == s.background);  // overshoots, as expected of sphere tracing
    s.distance = codegen(b.g, {b.g.min(f, sheet)}, {"d"});
    s.raw_field = true;
    Image raw = render(s, {});
    CHECK(test::all_finite(raw));
    glm::vec3 centre = px(raw, 32, 24);
    CHECK(centre.r > 0.3f);
    CHECK(centre.r > 4.0f * centre.g);
    CHECK(px(raw, 0, 0) == s.background);
    RenderOptions o;
    o.aovs = {"depth"};
    CHECK(render(s, o).aov("depth")->data[24 * 64 + 32] == Approx(4.0f).margin(0.01f));
    // Identical for any thread count here too.
    RenderOptions o1, o2;
    o1.threads = 1, o2.threads = 2;
    CHECK(render(s, o1).pixels == render(s, o2).pixels);
}

TEST_CASE("render: 2D models render as the Prospero image", "[render][2d]") {
    Builder b;
    NodeId disc = b.g.sub(b.g.binary(Op::Length2, b.x, b.y), b.c(0.5f));
    CompiledScene s = b.compile(disc, b.material({1, 1, 1}), 33, 33);
    s.is_2d = true;
    Image img = render(s, {});
    REQUIRE(img.channels == 1);  // render_2d's image, as `sdfc render` writes it
    CHECK(img.at(16, 16, 0) == 1.0f);  // (0, 0) inside
    CHECK(img.at(0, 0, 0) == 0.0f);    // (-1, 1) outside
    CHECK(img.at(16, 9, 0) == 1.0f);   // row 9: y = 1 - 9/16 = 0.4375, inside
    CHECK(img.at(16, 7, 0) == 0.0f);   // row 7: y = 0.5625, outside
    CHECK(img.pixels == render_2d(s, 33, 33).pixels);
    RenderOptions o;
    o.aovs = {"depth"};
    CHECK_THROWS_AS(render(s, o), std::invalid_argument);
}

TEST_CASE("image: png round trip, sRGB encoded", "[image]") {
    fs::path dir = temp_dir("png");
    Image img(16, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x) {
            img.at(x, y, 0) = x / 15.0f;
            img.at(x, y, 1) = y / 7.0f;
            img.at(x, y, 2) = 0.5f;
        }
    img.at(0, 0, 0) = NAN;    // written as 0
    img.at(1, 0, 0) = 40.0f;  // clamped to 1
    const std::string path = (dir / "out.png").string();
    write_image(path, img);
    Image back = read_image(path);
    REQUIRE(back.width == 16);
    REQUIRE(back.height == 8);
    REQUIRE(back.channels == 3);
    CHECK(back.at(0, 0, 0) == 0.0f);
    CHECK(back.at(1, 0, 0) == 1.0f);
    for (int y = 0; y < 8; ++y)
        for (int x = 2; x < 16; ++x)
            for (int c = 0; c < 3; ++c)
                CHECK(std::fabs(linear_to_srgb(back.at(x, y, c)) - linear_to_srgb(img.at(x, y, c))) <= 0.6f / 255.0f);
    // 0.5 linear is stored as sRGB 188.
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    CHECK(in->spec().format == OIIO::TypeDesc::UINT8);
    unsigned char px8[16 * 8 * 3];
    REQUIRE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px8));
    CHECK(static_cast<int>(px8[2]) == 188);
    fs::remove_all(dir);
}

TEST_CASE("image: exr round trip with AOV channels, png side files", "[image][aov]") {
    fs::path dir = temp_dir("exr");
    Builder b;
    CompiledScene s = red_sphere(b, 24, 16);
    RenderOptions o;
    o.aovs = {"depth", "normal", "steps"};
    Image img = render(s, o);
    const std::string exr = (dir / "out.exr").string();
    write_image(exr, img);
    {
        auto in = OIIO::ImageInput::open(exr);
        REQUIRE(in);
        std::vector<std::string> names = in->spec().channelnames;
        for (const char* want : {"R", "G", "B", "Z", "N.x", "N.y", "N.z", "steps.Y"})
            CHECK(std::find(names.begin(), names.end(), want) != names.end());
    }
    Image back = read_image(exr);
    REQUIRE(back.width == 24);
    REQUIRE(back.channels == 3);
    CHECK(back.pixels == img.pixels);
    for (const char* name : {"depth", "normal", "steps"}) {
        REQUIRE(back.aov(name));
        CHECK(back.aov(name)->data == img.aov(name)->data);
    }
    // Linear float formats keep values above 1.
    Image bright(2, 2);
    bright.pixels.assign(12, 3.5f);
    write_image((dir / "bright.exr").string(), bright);
    CHECK(read_image((dir / "bright.exr").string()).pixels[5] == 3.5f);

    // 8-bit formats write the AOVs as visualised side files.
    const std::string png = (dir / "shot.png").string();
    write_image(png, img);
    for (const char* name : {"depth", "normal", "steps"}) {
        fs::path side = dir / (std::string("shot.") + name + ".png");
        CHECK(fs::exists(side));
        CHECK(aov_side_path(png, name) == side.string());
        Image a = read_image(side.string());
        CHECK(a.width == 24);
    }
    fs::remove_all(dir);
}

TEST_CASE("image: written through a temporary file, replacing the target", "[image]") {
    fs::path dir = temp_dir("atomic");
    const std::string path = (dir / "frame.png").string();
    Image a(8, 8), c(8, 8);
    std::fill(a.pixels.begin(), a.pixels.end(), 0.0f);
    std::fill(c.pixels.begin(), c.pixels.end(), 1.0f);
    write_image(path, a);
    write_image(path, c);
    CHECK(read_image(path).pixels[0] == 1.0f);
    // Only the target is left in the folder: no temporary files.
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path().filename().string());
    CHECK(files == std::vector<std::string>{"frame.png"});

    // A failed write throws a readable error and leaves the existing target untouched.
    Image empty;
    CHECK_THROWS_AS(write_image(path, empty), std::runtime_error);
    CHECK(read_image(path).pixels[0] == 1.0f);
    try {
        write_image((dir / "no-such-dir" / "x.png").string(), c);
        FAIL("expected an error");
    } catch (const std::runtime_error& e) {
        CHECK(std::string(e.what()).find("x.png") != std::string::npos);
    }
    try {
        write_image((dir / "x.nosuchformat").string(), c);
        FAIL("expected an error");
    } catch (const std::runtime_error& e) {
        CHECK(std::string(e.what()).find("x.nosuchformat") != std::string::npos);
    }
    files.clear();
    for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path().filename().string());
    CHECK(files == std::vector<std::string>{"frame.png"});
    CHECK_THROWS_AS(read_image((dir / "missing.png").string()), std::runtime_error);
    fs::remove_all(dir);
}

// ---- issue 5: the richer renderer ----

TEST_CASE("render: ambient occlusion darkens a crease", "[render][ao]") {
    Builder b;
    // Floor (solid below y = 0) meeting a wall (solid at x > 1): a crease along x = 1, y = 0.
    NodeId d = b.g.min(b.floor(0), b.g.sub(b.c(1), b.x));
    CompiledScene s = b.compile(d, b.material({1, 1, 1}), 96, 64);
    s.camera.position = {-2, 2, 4};
    s.camera.target = {0.5f, 0, 0};
    s.lights[0].intensity = 0;  // ambient only
    s.ambient = glm::vec3(1);
    Image with_ao = render(s, {});
    s.render.ao = false;
    Image without = render(s, {});
    glm::vec2 crease = project(s, {0.98f, 0.02f, 0});
    glm::vec2 open = project(s, {-1.0f, 0, 0});
    CHECK(lum(px(without, crease)) == Approx(1.0f).margin(1e-4));
    CHECK(lum(px(with_ao, crease)) < 0.75f * lum(px(without, crease)));
    CHECK(lum(px(with_ao, open)) > 0.97f * lum(px(without, open)));
}

TEST_CASE("render: soft shadows add intermediate tones", "[render][shadow]") {
    // visibility fraction of each floor pixel = (shaded - ambient) / (unshadowed - ambient)
    auto partial_pixels = [](float radius, bool point) {
        Builder b;
        CompiledScene s = shadow_scene(b, radius, point);
        RenderOptions o;
        o.aovs = {"depth"};
        Image img = render(s, o);
        s.render.shadows = false;
        Image open = render(s, o);
        int partial = 0, dark = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                if (img.aov("depth")->data[y * img.width + x] < 4.99f) continue;  // the sphere, not the floor
                const float amb = 0.8f * 0.05f;
                const float v = (img.at(x, y, 0) - amb) / (open.at(x, y, 0) - amb);
                partial += v > 0.1f && v < 0.9f;
                dark += v <= 0.1f;
            }
        return std::pair{partial, dark};
    };
    for (bool point : {false, true}) {
        auto [hard_partial, hard_dark] = partial_pixels(0.0f, point);
        auto [soft_partial, soft_dark] = partial_pixels(point ? 0.6f : 0.1f, point);
        CHECK(hard_partial == 0);
        CHECK(hard_dark > 40);
        CHECK(soft_partial > 40);
        CHECK(soft_partial > hard_partial + 30);
    }
}

TEST_CASE("render: a mirror floor reflects a red sphere", "[render][reflect]") {
    auto scene = [](Builder& b, float reflect) {
        auto [d, m] = b.unite(b.sphere({0, 1, 0}, 1), b.material({1, 0.05f, 0.05f}, 0, 0, {0.3f, 0, 0}), b.floor(0),
                              b.material({0.6f, 0.6f, 0.6f}, reflect));
        CompiledScene s = b.compile(d, m, 80, 60);
        s.camera.position = {0, 1.5f, 6};
        s.camera.target = {0, 0.5f, 0};
        s.lights[0].position = {0, 0.5f, 5};
        s.lights[0].intensity = 20;
        return s;
    };
    Builder b1, b2;
    CompiledScene mirror = scene(b1, 1.0f), matte = scene(b2, 0.0f);
    const glm::vec2 floor_px = project(mirror, {0, 0, 1.5f});
    glm::vec3 m = px(render(mirror, {}), floor_px);
    glm::vec3 f = px(render(matte, {}), floor_px);
    CHECK(f.r == Approx(f.g).margin(1e-3));  // the matte floor is grey
    CHECK(m.r > 0.05f);
    CHECK(m.r > 3.0f * m.g);  // the mirror shows the red sphere
    // No bounces: the mirror is shaded as an opaque grey surface.
    mirror.render.max_bounces = 0;
    glm::vec3 none = px(render(mirror, {}), floor_px);
    CHECK(none.r == Approx(none.g).margin(1e-3));
}

TEST_CASE("render: a glass sphere refracts a striped wall", "[render][glass]") {
    auto scene = [](Builder& b, bool glass) {
        // A self-lit wall at z = -3 with vertical stripes 0.5 wide.
        NodeId wall = b.g.add(b.z, b.c(3));
        NodeId stripe = b.g.binary(Op::Lt, b.g.unary(Op::Fract, b.x), b.c(0.5f));
        MaterialN wm = b.material({0, 0, 0});
        for (int c : {kMatEmitR, kMatEmitG, kMatEmitB}) wm[c] = b.g.select(stripe, b.c(1), b.c(0));
        NodeId ball = b.sphere({0, 0, 0}, glass ? 1.0f : 0.0f);
        auto [d, m] = b.unite(ball, b.material({1, 1, 1}, 0, 1, {0, 0, 0}, 0, 1.5f), wall, wm);
        CompiledScene s = b.compile(glass ? d : wall, glass ? m : wm, 64, 64);
        s.camera.position = {0.1f, 0, 5};
        s.camera.target = {0.1f, 0, 0};
        s.lights[0].intensity = 0;
        s.ambient = glm::vec3(0);
        s.background = glm::vec3(0);
        return s;
    };
    Builder b1, b2;
    CompiledScene gs = scene(b1, true), ws = scene(b2, false);
    Image glass = render(gs, {}), wall = render(ws, {});
    int inside = 0, differ = 0;
    float glass_sum = 0, wall_sum = 0;
    const glm::vec2 c = project(gs, {0, 0, 0});
    const float radius_px = project(gs, {0.8f, 0, 0}).x - c.x;  // well inside the silhouette
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            if (std::hypot(x + 0.5f - c.x, y + 0.5f - c.y) > radius_px) continue;
            ++inside;
            const float g = lum(px(glass, x, y)), w = lum(px(wall, x, y));
            differ += (g > 0.5f) != (w > 0.5f);
            glass_sum += g, wall_sum += w;
        }
    REQUIRE(inside > 100);
    CHECK(differ > inside / 5);             // the stripes are displaced
    CHECK(glass_sum > 0.3f * wall_sum);     // and light passes through
    // Total internal reflection and exits stay finite; more bounces never add NaN.
    gs.render.max_bounces = 8;
    CHECK(test::all_finite(render(gs, {})));
}

TEST_CASE("render: more samples and cone tracing add edge tones", "[render][aa]") {
    Builder b;
    // A white self-lit sphere on black: one sample per pixel gives only 0 or 1.
    CompiledScene s = b.compile(b.sphere({0, 0, 0}, 1), b.material({0, 0, 0}, 0, 0, {1, 1, 1}), 48, 48);
    s.lights[0].intensity = 0;
    s.ambient = glm::vec3(0);
    s.background = glm::vec3(0);
    auto edge_tones = [&](const Image& img) {
        int n = 0;
        for (int i = 0; i < img.width * img.height; ++i) n += img.pixels[i * 3] > 0.05f && img.pixels[i * 3] < 0.95f;
        return n;
    };
    const int one = edge_tones(render(s, {}));
    s.render.samples = 4;
    Image four = render(s, {});
    s.render.samples = 16;
    Image sixteen = render(s, {});
    s.render.samples = 1;
    s.render.aa = "cone";
    Image cone = render(s, {});
    CHECK(one == 0);
    CHECK(edge_tones(four) > 30);
    CHECK(edge_tones(sixteen) >= edge_tones(four));
    CHECK(edge_tones(cone) > 30);
    // The centre stays fully covered, the corners empty.
    for (const Image* img : {&four, &sixteen, &cone}) {
        CHECK(img->at(24, 24, 0) == Approx(1.0f));
        CHECK(img->at(0, 0, 0) == 0.0f);
    }
}

// Timing, not run by default: `test_runtime "[.bench]"` (or "[bench]").
TEST_CASE("bench: 800x450 render", "[.bench]") {
    Builder b;
    auto [d, m] = b.unite(b.sphere({0, 1, 0}, 1), b.material({0.9f, 0.3f, 0.2f}, 0.0f, 0.0f, {0, 0, 0}, 0.5f), b.floor(0),
                          b.material({0.6f, 0.6f, 0.6f}));
    CompiledScene s = b.compile(d, m, 800, 450);
    s.camera.position = {0, 2, 6};
    s.camera.target = {0, 0.8f, 0};
    for (int threads : {1, 2}) {
        RenderOptions o;
        o.threads = threads;
        render(s, o);  // warm up
        double best = 1e30;
        RenderStats st;
        for (int i = 0; i < 3; ++i) {
            auto t0 = std::chrono::steady_clock::now();
            render(s, o, &st);
            best = std::min(best, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        }
        std::printf("800x450 sphere+plane, %d thread(s): %.1f ms, %.1f distance evals/pixel\n", threads, best,
                    double(st.distance_points) / (800.0 * 450.0));
    }
}
