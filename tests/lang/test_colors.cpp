// Named colours (issue 16, item 6): color("tomato") as OpenSCAD takes CSS names, and
// "#rrggbb"; sRGB made linear like every colour of a scene.
#include <catch2/catch.hpp>

#include <cmath>

#include "lang/css_colors.hpp"
#include "support.hpp"

using namespace sdfc;
using namespace sdfc::test;

namespace {

// The material colour at the origin (the shading program's colour outputs, linear).
glm::vec3 colour_of(const std::string& src) {
    auto c = compile_text(src);
    Evaluator ev(c->cs.shading);
    float x = 0, y = 0, z = 0;
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
