// compile_scene on a big scene: its distance and shading programs are generated on two
// threads at once (compiler/bytecode/compile.cpp, from 20,000 graph nodes); both must still
// compute the script's distance, and the same one.
#include <catch2/catch.hpp>

#include <string>

#include "support.hpp"

using namespace sdfc;

TEST_CASE("compile: a big scene's two programs give the script's distance") {
    // 80 x 80 spheres of radius 0.3 at integer points, every tenth one red.
    std::string src = "for (i = [0 : 79]) for (j = [0 : 79])\n"
                      "    translate([i, 0, j]) material(color = (i + j) % 10 == 0 ? [1, 0, 0] : [1, 1, 1]) sphere(0.3);\n";
    auto c = test::compile_text(src);
    REQUIRE(c->scene.graph->size() >= 20000);  // (the two-thread path)
    Evaluator distance(c->cs.distance), shading(c->cs.shading);
    REQUIRE(c->cs.shading.output_names.size() > 3);
    REQUIRE(c->cs.shading.output_names[0] == "d");
    struct Probe {
        float x, y, z, d;
    };
    const Probe probes[] = {
        {0, 0, 0, -0.3f},       {79, 0, 79, -0.3f},    {17, 0, 42, -0.3f},  {17.5f, 0, 42, 0.2f},
        {30, 1.3f, 30, 1.0f},   {-2, 0, 0, 1.7f},      {79, 0, 82, 2.7f},   {25, 0.3f, 33, 0.0f},
    };
    for (const Probe& p : probes) {
        INFO("at " << p.x << ", " << p.y << ", " << p.z);
        CHECK(distance.eval1(p.x, p.y, p.z) == Approx(p.d).margin(1e-5));
        CHECK(shading.eval1(p.x, p.y, p.z) == Approx(p.d).margin(1e-5));
    }
}
