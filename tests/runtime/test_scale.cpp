// Scale (issue 16, item 2): with no max_distance in the script, the far limit follows the
// scene's bounds and the camera, so a scene in millimetres renders as one in metres.
#include <catch2/catch.hpp>

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
