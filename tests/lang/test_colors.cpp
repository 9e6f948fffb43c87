// Named colours (issue 16, item 6): color("tomato") as OpenSCAD takes CSS names, and
// "#rrggbb"; sRGB made linear like every colour of a scene.
#include <catch2/catch.hpp>

#include <cmath>

#include "lang/css_colors.hpp"
#include "support.hpp"

using namespace sdfc;
using namespace sdfc::test;

namespace {

// The material colour at a point (the shading program's colour outputs, linear).
glm::vec3 colour_of(const std::string& src, float x = 0, float y = 0, float z = 0) {
    auto c = compile_text(src);
    Evaluator ev(c->cs.shading);
    ev.eval(&x, &y, &z, 1);
    return {ev.output(1 + kMatR)[0], ev.output(2 + kMatR)[0], ev.output(3 + kMatR)[0]};
}

float linear(int byte) {
    const float v = float(byte) / 255.0f;
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

TEST_CASE("color takes CSS names in any case and hex colours", "[lang]") {
    const glm::vec3 tomato(linear(255), linear(99), linear(71));
    for (const char* c : {"\"tomato\"", "\"Tomato\"", "\"TOMATO\"", "\"#ff6347\"", "\"#FF6347\""}) {
        INFO(c);
        const glm::vec3 got = colour_of(std::string("color(") + c + ") sphere(1);");
        CHECK(got.r == Approx(tomato.r));
        CHECK(got.g == Approx(tomato.g));
        CHECK(got.b == Approx(tomato.b));
    }
    const glm::vec3 short_hex = colour_of("color(\"#f63\") sphere(1);");
    CHECK(short_hex.g == Approx(linear(0x66)));
    CHECK(colour_of("color(\"gray\") sphere(1);").r == Approx(linear(128)));  // CSS's, not X11's 190
    CHECK(colour_of("color([1, 0.5, 0]) sphere(1);").g == Approx(0.5f));   // vectors stay as given
    CHECK(std::size(kCssColors) == 148);
    for (size_t i = 1; i < std::size(kCssColors); ++i) CHECK(std::string(kCssColors[i - 1].name) < kCssColors[i].name);
}

TEST_CASE("an unknown colour name says which it could be", "[lang]") {
    CHECK(first_error_line("color(\"tomatoe\") sphere(1);") == "test.sdf:1:7: error: unknown colour \"tomatoe\" (did you mean \"tomato\"?)");
    CHECK(first_error_line("color(\"nosuchxyz\") sphere(1);") ==
          "test.sdf:1:7: error: unknown colour \"nosuchxyz\" (a CSS name such as \"tomato\", or \"#rrggbb\")");
    CHECK(first_error_line("color(3) sphere(1);") == "test.sdf:1:7: error: color takes [r, g, b] or a colour name such as \"tomato\", not a number");
}

TEST_CASE("a colour field gives each point its colour, in local coordinates, blended by smooth operations", "[lang]") {
    const std::string checker = "color(field (p) -> (mod(floor(p.x) + floor(p.z), 2) < 1) ? [1, 1, 1] : [0, 0, 0]) box([8, 0.2, 8]);";
    CHECK(colour_of(checker, 0.5f, 0.1f, 0.5f).r == Approx(1.0f));
    CHECK(colour_of(checker, 1.5f, 0.1f, 0.5f).r == Approx(0.0f));
    CHECK(colour_of(checker, 1.5f, 0.1f, 1.5f).r == Approx(1.0f));
    // In the shape's own coordinates: translated with it.
    const std::string moved = "translate([10, 0, 0]) color(field (p) -> [p.x, 0, 0]) sphere(1);";
    CHECK(colour_of(moved, 10.5f, 0, 0).r == Approx(0.5f));
    // A smooth union blends it with its neighbour's colour between them.
    const std::string blend = "smooth_union(1) { color(field (p) -> [1, 0, 0]) sphere(1); translate([2, 0, 0]) color([0, 0, 1]) sphere(1); }";
    const glm::vec3 mid = colour_of(blend, 1, 0, 0);
    CHECK(mid.r == Approx(0.5f).margin(0.05f));
    CHECK(mid.b == Approx(0.5f).margin(0.05f));
    CHECK(first_error_line("color(field (p) -> 3) sphere(1);") == "test.sdf:1:20: error: a colour field must compute [r, g, b], not a number");
    // material(color = field ...) too, its other channels as given.
    CHECK(colour_of("material(color = field (p) -> [p.x, 0, 0], specular = 0.2) sphere(1);", 0.5f, 0, 0).r == Approx(0.5f));
}

TEST_CASE("every colour parameter takes a colour name: material, light, ambient, background", "[lang]") {
    const glm::vec3 tomato(linear(255), linear(99), linear(71));
    const glm::vec3 m = colour_of("material(color = \"tomato\", specular = 0, emission = \"black\") sphere(1);");
    CHECK(m.r == Approx(tomato.r));
    CHECK(m.b == Approx(tomato.b));
    auto c = compile_text("light(position = [1, 2, 3], color = \"#ff6347\");\nambient(\"white\");\nbackground(\"black\");\nsphere(1);");
    REQUIRE(c->cs.lights.size() == 1);
    CHECK(c->cs.lights[0].color.g == Approx(tomato.g));
    CHECK(c->cs.ambient == glm::vec3(1.0f));
    CHECK(c->cs.background == glm::vec3(0.0f));
    CHECK(first_error_line("light(color = \"tomatoe\");\nsphere(1);") ==
          "test.sdf:1:15: error: unknown colour \"tomatoe\" (did you mean \"tomato\"?)");
    CHECK(first_error_line("color(\"to\\\"mato\") sphere(1);") == "test.sdf:1:7: error: unknown colour \"to\\\"mato\" (did you mean \"tomato\"?)");
}
