// Scale (issue 16, item 2): with no max_distance in the script, the far limit follows the
// scene's bounds and the camera, so a scene in millimetres renders as one in metres.
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include "compiler/render/plan.hpp"
#include "runtime/cpu/tracer.hpp"
#include "support.hpp"

using namespace sdfc;
using namespace sdfc::test;

namespace {

RenderPlan plan_of(const CompiledScene& cs) { return plan_for(cs, false, {}); }

float centre_red(const std::string& src) {
    auto c = compile_text(src);
    c->cs.render.width = 32, c->cs.render.height = 24;
    const Image img = render(c->cs, {});
    return img.at(16, 12, 0);
}

}  // namespace

TEST_CASE("scale: the far limit fits the scene unless the script sets it", "[render]") {
    auto mm = compile_text("camera(position = [0, 0, 150]); sphere(20);");
    CHECK(plan_of(mm->cs).max_dist >= 170.0f * 1.01f - 1.0f);  // the bounds' farthest corner
    CHECK(plan_of(mm->cs).max_dist <= 4.0f * 150.0f + 1.0f);
    auto unit = compile_text("camera(position = [0, 0, 5]); sphere(1);");
    CHECK(plan_of(unit->cs).max_dist == 100.0f);  // the default, when it is enough
    auto set = compile_text("camera(position = [0, 0, 150]); render(max_distance = 100); sphere(20);");
    CHECK(plan_of(set->cs).max_dist == 100.0f);
    auto floor = compile_text("camera(position = [0, 60, 300], target = [0, 0, 0]); plane(); sphere(20);");
    CHECK(plan_of(floor->cs).max_dist >= 4.0f * 300.0f);  // a floor: four times the rest's distance
}

TEST_CASE("scale: a millimetre scene with default settings is not empty", "[render]") {
    CHECK(centre_red("camera(position = [0, 0, 150]); material(color = [1, 0, 0]) sphere(20);") > 0.05f);
    // The script's own limit is kept: this one stops short of the sphere.
    CHECK(centre_red("camera(position = [0, 0, 150]); render(max_distance = 100); material(color = [1, 0, 0]) sphere(20);") == 0.0f);
}

namespace {

// Surface pixels (a hit: depth under the far limit) that came out pure black.
int black_surface_pixels(const std::string& src, int w, int h) {
    auto c = compile_text(src);
    c->cs.render.width = w, c->cs.render.height = h;
    RenderOptions ro;
    ro.aovs = {"depth"};
    const Image img = render(c->cs, ro);
    const AovPlane* depth = img.aov("depth");
    REQUIRE(depth);
    const float far = plan_of(c->cs).max_dist;
    int black = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            if (!(depth->data[i] < 0.999f * far)) continue;
            black += img.at(x, y, 0) <= 0.0f && img.at(x, y, 1) <= 0.0f && img.at(x, y, 2) <= 0.0f;
        }
    return black;
}

}  // namespace

TEST_CASE("shading: no lit surface pixel is black (ambient occlusion at edges)", "[render]") {
    const std::string box = "camera(position = [3, 2.5, 4], target = [0, 0, 0]); background([0.5, 0.5, 0.5]); box([2, 0.5, 2]);";
    CHECK(black_surface_pixels(box, 640, 360) == 0);
    CHECK(black_surface_pixels("render(epsilon = 1e-3);" + box, 640, 360) == 0);
}

TEST_CASE("shading: no black pixels on a Menger field or a displaced plane at grazing angles", "[render]") {
    CHECK(black_surface_pixels(
              "camera(position = [3, 2, 4], target = [0, 0, 0]);\n"
              "def menger_cut(p, s) = { let a = mod(p * s, 2) - 1; let r = abs(1 - 3 * abs(a));\n"
              "  (min(max(r.x, r.y), min(max(r.y, r.z), max(r.z, r.x))) - 1) / (s * 3) };\n"
              "field (p) -> max(box(2)(p), max(menger_cut(p, 1), menger_cut(p, 3)));",
              320, 180) == 0);
    CHECK(black_surface_pixels("camera(position = [0, 0.4, 6], target = [0, 0, -10]); displace(0.05, 4) plane();", 320, 180) == 0);
}

TEST_CASE("exposure scales the picture's radiance, tone mapping maps it", "[render]") {
    const std::string scene = "camera(position = [0, 0, 5]); background([0.2, 0.1, 0.05]); sphere(1);";
    auto pixels = [&](const std::string& settings) {
        auto c = compile_text(settings + scene);
        c->cs.render.width = 16, c->cs.render.height = 12;
        return render(c->cs, {});
    };
    const Image plain = pixels(""), twice = pixels("render(exposure = 2);"), reinhard = pixels("render(tonemap = \"reinhard\");"),
                aces = pixels("render(exposure = 1, tonemap = \"aces\");");
    const float bg = plain.at(0, 0, 0);
    CHECK(bg == Approx(0.2f));
    CHECK(twice.at(0, 0, 0) == Approx(0.4f));
    CHECK(reinhard.at(0, 0, 0) == Approx(0.2f / 1.2f));
    const float x = 0.2f;
    CHECK(aces.at(0, 0, 0) == Approx((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f)));
    for (int y = 0; y < 12; ++y)
        for (int xx = 0; xx < 16; ++xx) {
            CHECK(twice.at(xx, y, 1) == Approx(2.0f * plain.at(xx, y, 1)));
            CHECK(aces.at(xx, y, 1) <= 1.0f);
        }
}

TEST_CASE("scale: a scene with the default lights looks the same from 0.01 to 1000 units", "[render]") {
    auto mean = [](float s) {
        const std::string src = fmt::format(
            "camera(position = [{0}, {1}, {2}], target = [0, 0, 0]); sphere({3}); translate([0, {4}, 0]) box([{5}, {6}, {5}]);",
            3 * s, 2 * s, 4 * s, s, -1.2f * s, 6 * s, 0.2f * s);
        auto c = compile_text(src);
        c->cs.render.width = 64, c->cs.render.height = 48;
        const Image img = render(c->cs, {});
        double sum = 0.0;
        for (float v : img.pixels) sum += v;
        return sum / double(img.pixels.size());
    };
    const double unit = mean(1.0f);
    CHECK(unit > 0.05);
    CHECK(mean(0.01f) == Approx(unit).epsilon(0.03));
    CHECK(mean(1000.0f) == Approx(unit).epsilon(0.03));
}
