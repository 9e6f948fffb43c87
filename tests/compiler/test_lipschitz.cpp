// The field the tracer marches must be 1-Lipschitz (Hart 1996): on every example, random
// point pairs 0.05 apart satisfy |f(p) - f(q)| <= 1.01 |p - q|.
#include <catch2/catch.hpp>

#include <filesystem>
#include <random>

#include "compiler/bytecode/compile.hpp"
#include "compiler/ir/op_math.hpp"
#include "lang/load.hpp"
#include "runtime/eval/vm.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> examples() {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(fs::path(SDFC_SOURCE_DIR) / "examples"))
        if (e.path().extension() == ".sdf") out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

// Worst ratio |f(p) - f(q)| / |p - q| over random pairs in the box around the camera target.
double worst_ratio(const CompiledScene& cs, int pairs, float extent, uint32_t seed) {
    Evaluator ev(cs.distance);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    glm::vec3 c = cs.camera.target;
    double worst = 0;
    float px[kBatch], py[kBatch], pz[kBatch], qx[kBatch], qy[kBatch], qz[kBatch], dist[kBatch];
    for (int done = 0; done < pairs; done += kBatch) {
        for (int i = 0; i < kBatch; ++i) {
            glm::vec3 p = c + extent * glm::vec3(u(rng), u(rng), u(rng));
            glm::vec3 d = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(1e-4f));
            glm::vec3 q = p + 0.05f * d;
            px[i] = p.x; py[i] = p.y; pz[i] = p.z;
            qx[i] = q.x; qy[i] = q.y; qz[i] = q.z;
            dist[i] = glm::length(q - p);
        }
        ev.eval(px, py, pz, kBatch);
        std::vector<float> fp(ev.output(0), ev.output(0) + kBatch);
        ev.eval(qx, qy, qz, kBatch);
        for (int i = 0; i < kBatch; ++i) worst = std::max(worst, std::fabs(double(fp[i]) - ev.output(0)[i]) / dist[i]);
    }
    return worst;
}

}  // namespace

TEST_CASE("every example's field is 1-Lipschitz") {
    for (const std::string& path : examples()) {
        SourceManager sm;
        CompiledScene cs = compile_scene(load_scene(sm, path));
        double w = worst_ratio(cs, 20000, 4.0f, 7);
        INFO(path << ": worst |f(p)-f(q)|/|p-q| = " << w);
        CHECK(w <= 1.01);
    }
}

TEST_CASE("distorting operations are scaled to stay 1-Lipschitz") {
    const char* scripts[] = {
        "scale([3, 1, 0.5]) sphere(1);",
        "twist(90) box([1, 3, 0.5]);",
        "bend(40) box([3, 0.3, 0.5]);",
        "displace(0.2, 3) sphere(1);",
        "ellipsoid([2, 0.5, 1]);",
        "gyroid(1, 0.1);",
        "schwarz_p(1, 0.1);",
        "field(bound = 3) (p) -> 3 * (length(p) - 1);",
        "smooth_union(0.5) { sphere(1); translate([1, 0.5, 0]) box(1); }",
        "chamfer_union(0.3) { sphere(1); translate([1, 0.5, 0]) box(1); }",
        "stairs_union(0.3, 4) { sphere(1); translate([1, 0.5, 0]) box(1); }",
        "round(0.2) twist(60) box([0.5, 2, 0.5]);",
        "repeat(1.5) sphere(0.5);",
        "polar_repeat(5) translate([1, 0, 0]) box(0.4);",
        "tri_prism(1, 1);",
        "pyramid(1.5);",
        "capped_torus(120, 1, 0.2);",
    };
    for (const char* s : scripts) {
        SourceManager sm;
        const SourceFile& f = sm.add("l.sdf", s);
        CompiledScene cs = compile_scene(interpret_source(sm, f));
        cs.camera.target = glm::vec3(0);
        double w = worst_ratio(cs, 20000, 2.5f, 11);
        INFO(s << ": worst ratio " << w);
        CHECK(w <= 1.01);
    }
}

TEST_CASE("the noise's Lipschitz constant bounds its measured gradient") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-20, 20), v(-1, 1);
    double worst = 0;
    for (int i = 0; i < 200000; ++i) {
        float x = u(rng), y = u(rng), z = u(rng);
        glm::vec3 d = glm::normalize(glm::vec3(v(rng), v(rng), v(rng)) + 1e-4f) * 0.01f;
        double r = std::fabs(om::noise3(x, y, z) - om::noise3(x + d.x, y + d.y, z + d.z)) / 0.01;
        worst = std::max(worst, r);
    }
    INFO("measured noise gradient bound " << worst);
    CHECK(worst <= om::kNoiseLipschitz);
    CHECK(worst > 0.5 * om::kNoiseLipschitz);  // and the constant is not wildly conservative
}
