// A raw field's ray columns (runtime/cpu/ray_columns.hpp): a ray of the family is never
// carried past a point where the field may change sign, they carry rays far, and a render with
// them draws what the baseline draws.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "compiler/render/rules.h"
#include "runtime/cpu/frame.hpp"
#include "runtime/cpu/ray_columns.hpp"
#include "runtime/cpu/tape_tree.hpp"
#include "runtime/cpu/tracer.hpp"
#include "runtime/eval/interval.hpp"
#include "shared_models.hpp"
#include "support.hpp"

using namespace sdfc;

namespace {

// 144 floating spheres (no floor: a floor plane would leave the rays unclipped), as in
// test_accel.cpp, and `light`.
std::string spheres(const std::string& light, int w = 160, int h = 90) {
    return "camera(position = [0, 9, 9], target = [0, 0, 0], fov = 45);\n" + light +
           "background([0.5, 0.6, 0.8]);\n"
           "render(width = " + std::to_string(w) + ", height = " + std::to_string(h) + ");\n"
           "for (i = [0:11], j = [0:11]) translate([(i - 5.5) * 10 / 12, 0.25, (j - 5.5) * 10 / 12]) sphere(10 / 30);\n";
}

uint32_t rng = 2468;
float uniform() {
    rng = rng * 1664525u + 1013904223u;
    return float(rng >> 8) / float(1 << 24);
}

struct Walk {
    int rays = 0, carried = 0, to_end = 0, wrong = 0;
    int start_clear = 0, start_clear_agrees = 0;  // samples clear to the end, by clear_until and by first_run too
    int carried_in_full = 0;  // samples carried that lie in a leaf not proven empty
};

// Whether the field may change sign at p: its leaf is not proven empty and, when `pointwise`,
// the leaf's tape at p itself (an interval of a box of one point) is not proven positive
// either (a light's columns leave out the pieces of a leaf proven positive: lay_chords).
struct SurfaceTest {
    const cpu::TapeTree& T;
    bool pointwise;
    IntervalEvaluator iv{T.max_regs, 64};
    struct Sample {
        bool full_leaf;    // in a leaf not proven empty
        bool may_change;   // the field may change sign at the point
    };
    Sample operator()(const glm::vec3& p) {
        const cpu::TapeTree::Leaf& leaf = T.leaves[T.locate(p.x, p.y, p.z)];
        const bool full = !(leaf.ivlo > 0.0f);
        if (!full || !pointwise) return {full, full};
        iv.eval(leaf.view(), &p.x, &p.x, &p.y, &p.y, &p.z, &p.z, 1, 0.0f);
        const Interval r = iv.result(0);
        return {true, !(cpu::raw_floor(r.lo, r.hi) > 0.0f)};
    }
};

// Where the ray o + t d is inside the box [lo, hi] shrunk by 1e-3 (a ray's end must be in
// the root): [ta, tb], as the renderers clip (ta = inf where the ray misses the box).
void clip_to_root(glm::vec3 lo, glm::vec3 hi, glm::vec3 o, glm::vec3 d, float& ta, float& tb) {
    ta = -INFINITY, tb = INFINITY;
    rules::sdf_clip_box(lo + 1e-3f, hi - 1e-3f, o, d, ta, tb);
}

// Along the ray o + t d over [t0, t1] (in the root), samples a 16th of the finest leaf
// apart: from each, clear_until (the ray's place kept, as a march keeps it) must not pass a
// sample where the field may change sign.
void walk(SurfaceTest& surface, const cpu::RayColumns& C, glm::vec3 o, glm::vec3 d, float t0, float t1, float h, Walk& w) {
    std::vector<float> ts;
    std::vector<char> change, in_full;
    for (float t = t0; t <= t1; t += h) {
        const SurfaceTest::Sample s = surface(o + d * t);
        ts.push_back(t);
        change.push_back(s.may_change);
        in_full.push_back(s.full_leaf);
    }
    std::vector<size_t> next_change(ts.size() + 1, ts.size());  // the first sample from j on where the sign may change
    for (size_t j = ts.size(); j-- > 0;) next_change[j] = change[j] ? j : next_change[j + 1];
    ++w.rays;
    uint32_t place = 0;
    for (size_t j = 0; j < ts.size(); ++j) {
        const float c = C.clear_until(o, d, ts[j], t1, place);
        if (!(c >= ts[j])) FAIL_CHECK("clear_until(" << ts[j] << ") = " << c);
        if (c > ts[j]) ++w.carried, w.carried_in_full += in_full[j];
        if (c == INFINITY) ++w.to_end;
        const size_t k = next_change[j];
        if (k < ts.size() && ts[k] < c) {
            ++w.wrong;
            FAIL_CHECK("carried from t = " << ts[j] << " to " << c << " past t = " << ts[k] << " (the field may change sign there)");
        }
        // A ray starting there (first_run: a march moves its start there, or does not march
        // it at all when that is past its end) obeys the same.
        uint32_t fresh = 0;
        const float f = C.first_run(o, d, ts[j], t1, fresh);
        if (!(f >= ts[j]) || (k < ts.size() && ts[k] < f)) {
            ++w.wrong;
            FAIL_CHECK("a ray from t = " << ts[j] << " starts at " << f << " (first sample where the field may change sign: "
                                         << (k < ts.size() ? ts[k] : INFINITY) << ")");
        }
        if (c == INFINITY) ++w.start_clear, w.start_clear_agrees += f == INFINITY;
    }
}

float finest_leaf(const cpu::TapeTree& T) {
    float f = INFINITY;
    for (uint32_t l = 1; l < T.leaves.size(); ++l) f = std::min(f, T.leaves[l].hi[0] - T.leaves[l].lo[0]);
    return f;
}

// `src` marked raw (as a .vm model is) and rendered, accelerated and as the baseline.
struct RawPair {
    std::unique_ptr<test::Compiled> c;
    Image fast{1, 1, 3}, base{1, 1, 3};
    RenderStats sf, sb;
};
RawPair render_raw(const std::string& src) {
    RawPair p;
    p.c = test::compile_text(src);
    p.c->cs.raw_field = true;
    RenderOptions ro;
    ro.threads = 2;
    p.fast = render(p.c->cs, ro, &p.sf);
    ro.baseline = true;
    p.base = render(p.c->cs, ro, &p.sb);
    REQUIRE(p.fast.pixels.size() == p.base.pixels.size());
    return p;
}

}  // namespace

TEST_CASE("columns: no ray is carried past a point where the field may change sign", "[columns]") {
    auto c = test::compile_text(spheres(""));
    cpu::TapeTree T;
    const glm::vec3 lo(-6, -1, -6), hi(6, 1, 6);
    cpu::build_tree(T, c->cs.distance, lo, hi, 0.0f, false, 160 * 90);
    REQUIRE(T.active);
    const float h = finest_leaf(T) / 16.0f;
    auto clip = [&](glm::vec3 o, glm::vec3 d, float& ta, float& tb) { clip_to_root(lo, hi, o, d, ta, tb); };

    SECTION("a directional light's rays, from points all over the root") {
        // Aslant, then straight down an axis and along a diagonal (the runs in a column are
        // the boxes' chords through it, bounded slab by slab: lay_chords; a slab across the
        // rays bounds none).
        cpu::ColumnsKey key;
        std::shared_ptr<const cpu::RayColumns> C;  // (the last light's, below)
        for (const glm::vec3 dir : {glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(1.0f, 1.0f, 1.0f), glm::vec3(0.4f, 1.0f, 0.3f)}) {
            key.dir = glm::normalize(dir);
            C = cpu::build_ray_columns(T, key);
            REQUIRE(C);
            CHECK_FALSE(C->central);
            Walk w;
            SurfaceTest surface{T, true};
            for (int r = 0; r < 600; ++r) {
                const glm::vec3 o = lo + (hi - lo) * glm::vec3(uniform(), uniform(), uniform());
                float ta, tb;
                clip(o, key.dir, ta, tb);
                walk(surface, *C, o, key.dir, 0.0f, tb, h, w);
            }
            INFO("light " << dir.x << ", " << dir.y << ", " << dir.z << ": rays " << w.rays << ", samples carried " << w.carried
                          << ", to the end " << w.to_end << ", in leaves not proven empty " << w.carried_in_full);
            CHECK(w.wrong == 0);
            // Pieces of leaves that hold surface are proven positive: rays pass through them.
            CHECK(w.carried_in_full > 0);
            CHECK(w.to_end > w.rays / 2);  // (most of the root's height is clear above the spheres)
            CHECK(w.start_clear > 0);
            CHECK(w.start_clear_agrees == w.start_clear);
        }
        // A ray not along the light is not the family's: the columns do not know it.
        uint32_t place = 0;
        const glm::vec3 d = glm::normalize(key.dir + glm::vec3(0.01f, 0, 0));
        CHECK(C->clear_until(glm::vec3(0, 0.9f, 0), d, 0.0f, 0.05f, place) == 0.0f);
        CHECK(place == cpu::RayColumns::kUnknown);
        // A ray of the family starting outside the root: nothing is known there, it starts
        // where it does.
        const glm::vec3 below = glm::vec3(0.0f, lo.y - 1.0f, 0.0f);
        place = 0;
        CHECK(C->first_run(below, key.dir, 0.0f, 1.5f, place) == 0.0f);
    }
    // A pinhole camera's columns (80 x 45 cells, vertical field of view `fov` degrees) and 300
    // of its rays walked from the eye, or from where they enter the root.
    auto camera_walk = [&](glm::vec3 eye, glm::vec3 fwd, float fov, std::shared_ptr<const cpu::RayColumns>& C) {
        const glm::vec3 right = glm::normalize(glm::cross(fwd, glm::vec3(0, 1, 0))), up = glm::cross(right, fwd);
        cpu::ColumnsKey key;
        key.central = true, key.dir = fwd, key.u = right, key.v = up, key.eye = eye;
        key.half_v = std::tan(glm::radians(fov / 2.0f)), key.half_u = key.half_v * 16.0f / 9.0f;
        key.cells_u = 80, key.cells_v = 45;
        C = cpu::build_ray_columns(T, key);
        Walk w;
        if (!C) return w;
        SurfaceTest surface{T, false};  // (a camera's columns hold whole leaves)
        for (int r = 0; r < 300; ++r) {
            const float a = (2.0f * uniform() - 1.0f) * key.half_u, b = (2.0f * uniform() - 1.0f) * key.half_v;
            const glm::vec3 d = glm::normalize(fwd + a * right + b * up);
            float ta, tb;
            clip(eye, d, ta, tb);
            ta = std::max(ta, 0.0f);
            if (!(ta < tb)) continue;
            walk(surface, *C, eye, d, ta, tb, h, w);
        }
        return w;
    };
    SECTION("a camera's rays, from its eye") {
        const glm::vec3 eye(0, 9, 9), fwd = glm::normalize(-eye);
        std::shared_ptr<const cpu::RayColumns> C;
        const Walk w = camera_walk(eye, fwd, 45.0f, C);
        REQUIRE(C);
        CHECK(C->central);
        INFO("rays " << w.rays << ", samples carried " << w.carried << ", to the end " << w.to_end);
        CHECK(w.rays > 150);
        CHECK(w.wrong == 0);
        CHECK(w.carried > 0);
        // A ray not from the eye is not the family's: the columns do not know it.
        uint32_t place = 0;
        const glm::vec3 o = eye + glm::vec3(0.5f, 0, 0);
        CHECK(C->clear_until(o, fwd, 10.0f, 11.0f, place) == 10.0f);
        CHECK(place == cpu::RayColumns::kUnknown);
    }
    SECTION("a camera's rays, from an eye among the spheres") {
        // Leaves around the eye and beside it reach the eye's plane: each covers the columns
        // on its side of the view (all of them only when it holds the eye), so rays are still
        // carried over the open space (measured: 8,920 samples carried to the end; 74 when
        // every leaf reaching the eye's plane covered every column).
        std::shared_ptr<const cpu::RayColumns> C;
        const Walk w = camera_walk(glm::vec3(0.1f, 0.5f, 0.2f), glm::normalize(glm::vec3(1, -0.1f, 0.7f)), 80.0f, C);
        REQUIRE(C);
        INFO("rays " << w.rays << ", samples carried " << w.carried << ", to the end " << w.to_end);
        CHECK(w.rays > 150);
        CHECK(w.wrong == 0);
        CHECK(w.to_end > 10 * w.rays);
    }
}

TEST_CASE("columns: a raw field's camera and directional shadow rays go from run to run, drawing the baseline's picture",
          "[columns]") {
    // Marked raw (as a .vm model), lit by a directional light: camera rays and shadow rays
    // are carried along their columns. A sphere high above a corner makes the scene's box
    // (where rays are clipped) tall, so the rays cross empty space. The baseline marches
    // sample by sample: the pictures are 38.4 dB apart, 44 values off by more than 8 levels
    // in 255 (measured; before the camera rays' steps just past a predicted zero, rules.h
    // sdf_raw_step: 36.8 dB and 59, the same with the columns as without them, and the
    // jumps 61,792 -> 43,488): raw marching's own differences (test_accel.cpp).
    RawPair r = render_raw(spheres("light(direction = [-0.4, -1, -0.3], intensity = 2);\n") + "translate([5, 3, 5]) sphere(0.3);\n");
    const Image &a = r.fast, &b = r.base;
    const RenderStats& fast = r.sf;
    // (PSNR of the 8-bit sRGB pictures, as test_accel.cpp measures)
    const double psnr = test::psnr_srgb8(a, b);
    int off = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) off += std::abs(test::srgb8(a.pixels[i]) - test::srgb8(b.pixels[i])) > 8.0f;
    INFO("column skips " << fast.column_skips << " of " << fast.skips << ", psnr " << psnr << ", values off " << off);
    CHECK(fast.column_skips > 0);
    CHECK(fast.column_skips <= fast.skips);
    CHECK(fast.shadow_cuts == 0);  // (the columns end the shadow rays instead)
    CHECK(psnr >= 36.5);

    // The same scene as a distance: its rays step on distances, no columns.
    r.c->cs.raw_field = false;
    RenderOptions ro;
    ro.threads = 2;
    RenderStats d;
    render(r.c->cs, ro, &d);
    CHECK(d.column_skips == 0);
}

TEST_CASE("columns: an orthographic camera's rays are carried along parallel columns", "[columns]") {
    // The same spheres seen through an orthographic camera: its rays are parallel, like a
    // directional light's, and start on the view's plane, not at one eye. Against the
    // baseline, 53 of the 43,200 values are off by more than 0.05 (measured; 52 before the
    // camera rays' steps just past a predicted zero, the same with the columns as without
    // them then): raw marching's own differences.
    std::string src = spheres("light(direction = [-0.4, -1, -0.3], intensity = 2);\n") + "translate([5, 3, 5]) sphere(0.3);\n";
    src.replace(src.find("fov = 45"), 8, "projection = \"orthographic\", ortho_height = 14");
    RawPair r = render_raw(src);
    const Image &a = r.fast, &b = r.base;
    const RenderStats& fast = r.sf;
    int off = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) off += std::abs(std::clamp(a.pixels[i], 0.0f, 1.0f) - std::clamp(b.pixels[i], 0.0f, 1.0f)) > 0.05f;
    INFO("column skips " << fast.column_skips << " of " << fast.skips << ", values off " << off << " of " << a.pixels.size());
    CHECK(fast.column_skips > 0);
    CHECK(off <= 60);

    // Without shadows, only the camera's rays jump.
    r.c->cs.render.shadows = false;
    RenderOptions ro;
    ro.threads = 2;
    RenderStats cam;
    render(r.c->cs, ro, &cam);
    INFO("camera rays' column skips " << cam.column_skips << " of " << cam.skips);
    CHECK(cam.column_skips > 0);
}

TEST_CASE("columns: colonnade.vm's lights carry no ray past a point where the field may change sign", "[columns]") {
    // A public model of planes and cylinders (../shared), its tree and lights as a 1024^2
    // render makes them: 3,000 rays along each directional light from points all over the root.
    const auto model = test::shared_model("colonnade.vm");
    if (!model) return;
    CompiledScene& cs = model->cs;
    cs.render.width = 1024, cs.render.height = 1024;
    const RenderOptions ro;
    const cpu::Frame f = cpu::make_frame(cs, ro);
    glm::vec3 lo, hi;
    bool thin = false;
    REQUIRE(cpu::tree_root(f, cs, ro, lo, hi, &thin));
    cpu::TapeTree T;
    cpu::build_tree(T, cs.distance, lo, hi, 0.0f, false, 1024 * 1024, thin);
    REQUIRE(T.active);
    const float h = finest_leaf(T) / 16.0f;
    int lights = 0;
    for (const ResolvedLight& L : f.lights) {
        if (!L.directional) continue;
        ++lights;
        cpu::ColumnsKey key;
        key.dir = glm::normalize(-L.direction);
        const auto C = cpu::build_ray_columns(T, key);
        REQUIRE(C);
        Walk w;
        SurfaceTest surface{T, true};
        for (int r = 0; r < 3000; ++r) {
            const glm::vec3 o = lo + (hi - lo) * glm::vec3(uniform(), uniform(), uniform());
            float ta, tb;
            clip_to_root(lo, hi, o, key.dir, ta, tb);
            walk(surface, *C, o, key.dir, 0.0f, tb, h, w);
        }
        INFO("light " << lights << ": rays " << w.rays << ", samples carried " << w.carried << ", in leaves not proven empty "
                      << w.carried_in_full);
        CHECK(w.wrong == 0);
        CHECK(w.carried_in_full > 0);
    }
    CHECK(lights > 0);
}
