// The render plan (compiler/render/plan.cpp) and the shared per-ray rules
// (compiler/render/rules.h): settings resolve once, to the numbers both renderers read.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include "compiler/render/plan.hpp"
#include "compiler/render/rules.h"
#include "support.hpp"

using namespace sdfc;

namespace {

RenderPlan plan_of(const std::string& src, bool baseline = false) {
    auto c = test::compile_text(src);
    if (c->scene.lights.empty()) c->cs.lights.clear();  // (compile_text gives tests the rig)
    Evaluator ev(c->cs.distance);
    return plan_for(c->cs, baseline, [&](const float* x, const float* y, const float* z, size_t n, float* out) {
        for (size_t i = 0; i < n; ++i) out[i] = ev.eval1(x[i], y[i], z[i]);
    });
}

}  // namespace

TEST_CASE("plan: settings are clamped and defaulted once") {
    // The script checks its own numbers; a CompiledScene made by hand (the library's users)
    // is clamped by the plan.
    auto c = test::compile_text("sphere(1);");
    c->cs.render.width = 0, c->cs.render.height = 3, c->cs.render.samples = 5000, c->cs.render.max_steps = 0;
    c->cs.render.max_bounces = 99;
    const RenderPlan p = plan_for(c->cs, false, {});
    CHECK(p.width == 1);
    CHECK(p.height == 3);
    CHECK(p.samples == 4096);
    CHECK(p.offsets.size() == 4096);
    CHECK(p.max_steps == 1);
    CHECK(p.max_bounces == 64);
    CHECK(p.min_weight == Approx(1e-3f / 4096.0f));
    c->cs.render.epsilon = 0.0f, c->cs.render.max_distance = -1.0f;
    const RenderPlan q = plan_for(c->cs, false, {});
    CHECK(q.eps == 1e-4f);
    CHECK(q.max_dist == 100.0f);
}

TEST_CASE("plan: sample offsets are a Hammersley set, the same for every renderer") {
    const std::vector<glm::vec2> o = sample_offsets(4);
    REQUIRE(o.size() == 4);
    CHECK(o[0] == glm::vec2(0.125f, 0.125f));
    CHECK(o[1] == glm::vec2(0.375f, 0.625f));
    CHECK(o[2] == glm::vec2(0.625f, 0.375f));
    CHECK(o[3] == glm::vec2(0.875f, 0.875f));
    CHECK(sample_offsets(1) == std::vector<glm::vec2>{glm::vec2(0.5f, 0.5f)});
}

TEST_CASE("plan: the clip box has its margin, floor planes become half-spaces, baseline turns clipping off") {
    const RenderPlan p = plan_of("sphere(1);");
    CHECK(p.clip);
    CHECK(p.lo.x == Approx(-1.0f - (2e-3f + 1e-3f)));
    CHECK(p.hi.y == Approx(1.0f + 3e-3f));
    CHECK(p.planes.empty());
    CHECK(p.relax == 1.5f);
    CHECK(p.premarch);

    const RenderPlan f = plan_of("plane();\ntranslate([0, 1, 0]) sphere(1);");
    CHECK_FALSE(f.clip);
    REQUIRE(f.planes.size() == 1);
    CHECK(f.planes[0].y == 1.0f);
    CHECK(f.planes[0].w == Approx(2e-3f + 1e-3f));  // margin of the box of the rest, plus 1e-3
    CHECK(f.solid_lo.y == Approx(0.0f - 3e-3f));

    const RenderPlan b = plan_of("plane();\nsphere(1);", true);
    CHECK(b.planes.empty());
    CHECK_FALSE(b.clip);
    CHECK(b.relax == 1.0f);
    CHECK_FALSE(b.premarch);
}

TEST_CASE("plan: a script without lights gets the default rig, one with lights keeps them") {
    const RenderPlan p = plan_of("sphere(1);");
    CHECK(p.default_lights);
    REQUIRE(p.lights.size() == 2);
    CHECK(p.lights[0].directional);
    CHECK(glm::length(p.lights[0].direction) == Approx(1.0f));
    CHECK(p.lights[0].color == rules::sdf_key_light_color());
    CHECK(p.lights[1].intensity == rules::sdf_fill_light_intensity());
    const RenderPlan q = plan_of("light(position = [1, 2, 3], intensity = 5);\nsphere(1);");
    CHECK_FALSE(q.default_lights);
    REQUIRE(q.lights.size() == 1);
    CHECK(q.lights[0].position == glm::vec3(1, 2, 3));
}

TEST_CASE("plan: cone anti-aliasing traces one cone per pixel, raw fields get no AO but a box and a Lipschitz estimate") {
    const RenderPlan c = plan_of("render(aa = \"cone\", samples = 9);\nsphere(1);");
    CHECK(c.cone);
    CHECK(c.samples == 1);
    CHECK_FALSE(c.premarch);
    // A .vm-like raw field: the plan is resolved from a CompiledScene marked raw.
    auto s = test::compile_text("field (p) -> length(p) * 3 - 3;");
    s->cs.raw_field = true;
    Evaluator ev(s->cs.distance);
    const RenderPlan r = plan_for(s->cs, false, [&](const float* x, const float* y, const float* z, size_t n, float* out) {
        for (size_t i = 0; i < n; ++i) out[i] = ev.eval1(x[i], y[i], z[i]);
    });
    CHECK(r.raw);
    CHECK_FALSE(r.ao);
    CHECK(r.clip);
    CHECK(r.raw_lipschitz == Approx(4.5f).epsilon(0.02));  // |grad| = 3, times 1.5
    CHECK(r.raw_max_step == Approx(glm::length(r.hi - r.lo) / 48.0f));
}

TEST_CASE("rules: material fallbacks are the material table's defaults") {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    CHECK(rules::sdf_safe_shininess(nan) == kMatChannelInfo[kMatShininess].def);
    CHECK(rules::sdf_safe_ior(nan) == kMatChannelInfo[kMatIor].def);
    CHECK(rules::sdf_safe_ior(0.0f) == kMatChannelInfo[kMatIor].def);
    CHECK(rules::sdf_safe_shininess(1e9f) == 1e4f);
    CHECK(rules::sdf_nonneg(inf) == 1e30f);
    CHECK(rules::sdf_nonneg(nan) == 0.0f);
    CHECK(rules::sdf_clamp01(2.0f) == 1.0f);
}

TEST_CASE("rules: relaxed steps, hits, and the raw field's secant steps and refinement") {
    // Far from anything: an over-relaxed step of 1.5 d.
    float t = 1.0f, om = 1.5f, pr = 0.0f, sl = 0.0f, last = 0.0f;
    CHECK_FALSE(rules::sdf_relaxed_step(2.0f, 0.0f, 100.0f, false, 1, 256, 1e-4f, t, om, pr, sl, last));
    CHECK(t == 4.0f);
    CHECK(last == 2.0f);
    // The next sphere does not overlap the previous one: back to its boundary, omega 1.
    CHECK_FALSE(rules::sdf_relaxed_step(0.5f, 0.0f, 100.0f, false, 2, 256, 1e-4f, t, om, pr, sl, last));
    CHECK(om == 1.0f);
    CHECK(t == 3.0f);  // the previous sphere's boundary: 1 + 2
    CHECK(std::isinf(last));
    // Under the threshold: a hit, moved on by its last distance.
    float t2 = 3.0f, om2 = 1.0f, pr2 = 0.0f, sl2 = 0.0f, last2 = 0.0f;
    CHECK(rules::sdf_relaxed_step(1e-5f, 0.0f, 100.0f, false, 3, 256, 1e-4f, t2, om2, pr2, sl2, last2));
    const bool hit = rules::sdf_relaxed_hit(last2, t2, 3, 256, 1e-4f, 0.0f, 1e-3f);
    CHECK(hit);
    CHECK(rules::sdf_hit_t(t2, last2, hit) == 3.0f + 1e-5f);
    // Raw field: a sign change brackets [prev, t]; without the value at prev, it is halved.
    float rt = 1.0f, prev = 0.5f, pv = NAN, hi = 0.0f, fhi = 0.0f, refine = 0.0f;
    bool rhit = false;
    CHECK_FALSE(
        rules::sdf_raw_step(-1.0f, 0.0f, 10.0f, false, 1, 256, 1e-4f, 0.0f, 1e-3f, 1.0f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(prev == 0.5f);
    CHECK(hi == 1.0f);
    CHECK(fhi == -1.0f);
    CHECK(refine == 1.0f);
    CHECK(rt == 0.75f);
    // With it, the chord's zero (0.875 for values 3 and -1), then 0.45 thresholds toward
    // the end farther from it (prev).
    rt = 1.0f, prev = 0.5f, pv = 3.0f, refine = 0.0f;
    CHECK_FALSE(
        rules::sdf_raw_step(-1.0f, 0.0f, 10.0f, false, 1, 256, 1e-4f, 0.0f, 1e-3f, 1.0f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(rt == Approx(0.875f - 0.45e-4f).epsilon(1e-6));
    // Positive there: the bracket is [rt, 1], over a threshold wide: the next probe. Then
    // negative within a threshold of it: a hit at the outside end.
    const float probe = rt;
    CHECK_FALSE(
        rules::sdf_raw_step(0.1f, 0.0f, 10.0f, false, 2, 256, 1e-4f, 0.0f, 1e-3f, 1.0f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(prev == probe);
    rt = probe + 0.5e-4f;
    CHECK(rules::sdf_raw_step(-0.1f, 0.0f, 10.0f, false, 3, 256, 1e-4f, 0.0f, 1e-3f, 1.0f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(rhit);
    CHECK(rt == probe);
    // Marching: a footprint-sized step (|f| / L under a footprint) where the secant of the last
    // two samples (1 at 0, 0.5 at 0.5) puts the zero 0.5 ahead: 2 footprints instead of 1.
    rt = 0.5f, prev = 0.0f, pv = 1.0f, refine = 0.0f;
    CHECK_FALSE(
        rules::sdf_raw_step(0.5f, 0.0f, 10.0f, false, 2, 256, 1e-4f, 0.0f, 1e-3f, 1e-3f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(prev == 0.5f);
    CHECK(pv == 0.5f);
    CHECK(rt == Approx(0.5f + 2.0f * 0.5e-3f).epsilon(1e-6));
    // A shadow ray (any sign change ends it) keeps the footprint where the field falls, and
    // takes two where it rises.
    rt = 0.5f, prev = 0.0f, pv = 1.0f, refine = 0.0f;
    CHECK_FALSE(
        rules::sdf_raw_step(0.5f, 0.0f, 10.0f, true, 2, 256, 1e-4f, 0.0f, 1e-3f, 1e-3f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(rt == Approx(0.5f + 0.5e-3f).epsilon(1e-6));
    rt = 0.5f, prev = 0.0f, pv = 0.25f, refine = 0.0f;
    CHECK_FALSE(
        rules::sdf_raw_step(0.5f, 0.0f, 10.0f, true, 2, 256, 1e-4f, 0.0f, 1e-3f, 1e-3f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(rt == Approx(0.5f + 2.0f * 0.5e-3f).epsilon(1e-6));
    // Rising: no secant, one footprint.
    rt = 0.5f, prev = 0.0f, pv = 0.25f, refine = 0.0f;
    CHECK_FALSE(
        rules::sdf_raw_step(0.5f, 0.0f, 10.0f, false, 2, 256, 1e-4f, 0.0f, 1e-3f, 1e-3f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(rt == Approx(0.5f + 0.5e-3f).epsilon(1e-6));
    // A camera ray whose secant (1 at 0, 1e-5 at 1) puts the zero 1e-5 ahead, inside its
    // footprint step (1e-3): half a threshold (0.5e-4) past the zero instead, marked in hi.
    rt = 1.0f, prev = 0.0f, pv = 1.0f, hi = 0.0f, refine = 0.0f;
    CHECK_FALSE(
        rules::sdf_raw_step(1e-5f, 0.0f, 10.0f, false, 2, 256, 1e-4f, 0.0f, 1e-3f, 1e-3f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    const float close_t = 1.0f + 1e-5f / (1.0f - 1e-5f) + 0.5e-4f;
    CHECK(rt == Approx(close_t).epsilon(1e-7));
    CHECK(hi == rt);
    CHECK(prev == 1.0f);
    // Negative there: the bracket [1, rt] is under a threshold: a hit at its outside end,
    // with no refinement.
    rhit = false;
    CHECK(rules::sdf_raw_step(-1e-6f, 0.0f, 10.0f, false, 3, 256, 1e-4f, 0.0f, 1e-3f, 1e-3f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(rhit);
    CHECK(rt == 1.0f);
    CHECK(refine == 0.0f);
    // Positive there (a ray passing close to a surface): no second such step in a row, the
    // footprint step (its secant's zero, 6e-5 ahead, is short of it).
    rt = close_t, prev = 1.0f, pv = 1e-5f, hi = close_t, refine = 0.0f;
    CHECK_FALSE(
        rules::sdf_raw_step(5e-6f, 0.0f, 10.0f, false, 4, 256, 1e-4f, 0.0f, 1e-3f, 1e-3f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(rt == Approx(close_t + 1e-3f * close_t).epsilon(1e-7));
    CHECK(hi == close_t);
    // A shadow ray takes its footprint step (any sign change ends it anyway).
    rt = 1.0f, prev = 0.0f, pv = 1.0f, hi = 0.0f, refine = 0.0f;
    CHECK_FALSE(
        rules::sdf_raw_step(1e-5f, 0.0f, 10.0f, true, 2, 256, 1e-4f, 0.0f, 1e-3f, 1e-3f, 1.0f, rt, prev, pv, hi, fhi, refine, rhit));
    CHECK(rt == Approx(1.0f + 1e-3f).epsilon(1e-7));
    CHECK(rules::sdf_to_srgb(0.0031308f) == Approx(0.04045f).epsilon(1e-3));
    CHECK(rules::sdf_to_srgb(2.0f) == 1.0f);
    CHECK(rules::sdf_grid_x(0, 5) == -1.0f);
    CHECK(rules::sdf_grid_x(4, 5) == 1.0f);
    CHECK(rules::sdf_grid_y(0, 5) == 1.0f);
}

TEST_CASE("rules: the tile pre-march begins no later than its cone first meets the box") {
    const glm::vec3 lo(-1.0f), hi(1.0f);
    // Distance from the point to the box (0 inside).
    auto box_dist = [&](glm::vec3 p) { return glm::length(glm::max(glm::max(lo - p, p - hi), glm::vec3(0.0f))); };
    const float far = 100.0f;
    // From inside the box: at once.
    CHECK(rules::sdf_premarch_begin(lo, hi, glm::vec3(0.5f), glm::vec3(0, 0, -1), glm::vec2(0.1f, 0.01f), far) == 0.0f);
    // Axis at the box: near the entry (t = 9 less the radius), never after the cone touches it.
    struct Case {
        glm::vec3 o;
        glm::vec2 r;
        float touch;  // where the cone (o + t (0, 0, -1), radius r0 + r1 t) first meets the box
    };
    for (const Case& c : {Case{{0, 0, 10}, {0.1f, 0.01f}, 9.0f - 0.19f / 1.01f}, Case{{0, 1.5f, 10}, {0.6f, 0.0f}, 9.0f - std::sqrt(0.36f - 0.25f)},
                          Case{{0, 1.5f, 10}, {0.3f, 0.03f}, 0.0f}}) {
        const float t = rules::sdf_premarch_begin(lo, hi, c.o, glm::vec3(0, 0, -1), c.r, far);
        INFO("o.y " << c.o.y << " begin " << t);
        REQUIRE(t < far);
        for (float s = 0.0f; s <= t; s += 0.01f) CHECK(box_dist(c.o + s * glm::vec3(0, 0, -1)) > c.r.x + c.r.y * s);
        if (c.touch > 0.0f) CHECK(t > c.touch - 0.5f);  // and not much earlier
    }
    // A cone that misses the box: the max distance, nothing to march.
    CHECK(rules::sdf_premarch_begin(lo, hi, glm::vec3(0, 1.5f, 10), glm::vec3(0, 0, -1), glm::vec2(0.4f, 0.0f), far) == far);
}
