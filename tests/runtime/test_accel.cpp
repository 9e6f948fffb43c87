// The accelerated tracer (tape tree, empty-space jumps, over-relaxation, bounds clipping)
// against RenderOptions::baseline (plain Hart tracing on the full program): pictures
// within PSNR 45 dB, fewer evaluations, determinism across thread counts, progress.
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "lang/load.hpp"
#include "runtime/cpu/frame.hpp"
#include "runtime/cpu/tape_tree.hpp"
#include "runtime/cpu/tracer.hpp"
#include "runtime/cpu/tree_cache.hpp"
#include "runtime/eval/interval.hpp"
#include "support.hpp"

using namespace sdfc;

namespace {

// PSNR of the 8-bit sRGB pictures (what a PNG would hold), in dB.
double psnr(const Image& a, const Image& b) {
    REQUIRE(a.width == b.width);
    REQUIRE(a.height == b.height);
    REQUIRE(a.pixels.size() == b.pixels.size());
    return test::psnr_srgb8(a, b);
}

// A k x k grid of spheres on a floor, seen from above at an angle, one light.
std::string grid_scene(int k, int w = 160, int h = 90, bool floor = true) {
    const double c = 10.0 / k;
    return "camera(position = [0, 9, 9], target = [0, 0, 0], fov = 45);\n"
           "light(position = [6, 12, 8], intensity = 200);\n"
           "background([0.5, 0.6, 0.8]);\n"
           "render(width = " + std::to_string(w) + ", height = " + std::to_string(h) + ");\n" +
           std::string(floor ? "plane([0, 1, 0], 0);\n" : "") +
           "for (i = [0:" + std::to_string(k - 1) + "], j = [0:" + std::to_string(k - 1) + "]) translate([(i - " +
           std::to_string(k) + " / 2 + 0.5) * " + std::to_string(c) + ", 0.3 * " + std::to_string(c) + ", (j - " +
           std::to_string(k) + " / 2 + 0.5) * " + std::to_string(c) + "]) sphere(" + std::to_string(0.4 * c) + ");\n";
}

struct Pair {
    Image accel{1, 1, 3}, base{1, 1, 3};
    RenderStats sa, sb;
};

Pair render_both(const CompiledScene& cs, int threads = 2) {
    Pair p;
    RenderOptions ro;
    ro.threads = threads;
    p.accel = render(cs, ro, &p.sa);
    ro.baseline = true;
    p.base = render(cs, ro, &p.sb);
    return p;
}

// The scene rendered (accelerated and baseline) as a distance, then marked raw (as a .vm
// model is: no distance bound, sign-change steps).
struct DistanceAndRaw {
    Pair d, r;
};
DistanceAndRaw render_distance_and_raw(const std::string& src) {
    auto c = test::compile_text(src);
    DistanceAndRaw out;
    out.d = render_both(c->cs);
    c->cs.raw_field = true;
    out.r = render_both(c->cs);
    return out;
}

}  // namespace

TEST_CASE("accel: a 12 x 12 grid of spheres matches the baseline, with far fewer instructions", "[accel]") {
    auto c = test::compile_text(grid_scene(12));
    const Pair p = render_both(c->cs);
    INFO("psnr " << psnr(p.accel, p.base));
    CHECK(psnr(p.accel, p.base) >= 45.0);
    // The tree was built and used; the baseline has none.
    CHECK(p.sa.tree_leaves > 0);
    CHECK(p.sb.tree_leaves == 0);
    CHECK(p.sb.skips == 0);
    // SDF evaluations (points): fewer than plain Hart tracing (measured: 22% fewer; rays
    // and shadow rays, while normals and AO taps cost the same), and much cheaper ones
    // (instructions run).
    const double ea = double(p.sa.distance_points), eb = double(p.sb.distance_points);
    INFO("evals accel " << ea << " baseline " << eb);
    CHECK(ea <= 0.85 * eb);
    CHECK(p.sa.distance_points_by[RenderStats::kRays] < p.sb.distance_points_by[RenderStats::kRays]);
    CHECK(p.sa.distance_points_by[RenderStats::kShadows] < p.sb.distance_points_by[RenderStats::kShadows]);
    CHECK(p.sa.distance_points_by[RenderStats::kNormals] == p.sb.distance_points_by[RenderStats::kNormals]);
    INFO("instructions accel " << p.sa.distance_instructions << " baseline " << p.sb.distance_instructions);
    CHECK(p.sa.distance_instructions * 4 <= p.sb.distance_instructions);
}

TEST_CASE("accel: rays jump over the tree's empty cells", "[accel]") {
    // recursive1: three fields (no bounding box), 214 instructions: a tree, and rays
    // between the sponges cross its empty cells.
    SourceManager sm;
    CompiledScene cs = compile_scene(load_scene(sm, std::string(SDFC_SOURCE_DIR) + "/examples/recursive1.sdf"));
    cs.render.width = 320;
    cs.render.height = 180;
    cs.render.samples = 1;
    const Pair p = render_both(cs);
    CHECK(p.sa.tree_leaves > 0);
    CHECK(p.sa.skips > 0);
    CHECK(p.sb.skips == 0);
    CHECK(p.sa.distance_instructions * 3 < p.sb.distance_instructions);
}

TEST_CASE("accel: smooth unions and twisted shapes match the baseline", "[accel]") {
    auto c = test::compile_text(R"(
camera(position = [0, 3, 7], target = [0, 0.5, 0], fov = 45);
light(position = [4, 6, 5], intensity = 80, radius = 0.5);
light(direction = [-0.3, -1, -0.4], intensity = 0.4);
background([0.6, 0.7, 0.8]);
render(width = 160, height = 100);
material(color = [0.8, 0.8, 0.75]) plane([0, 1, 0], 0);
smooth_union(0.3) {
  material(color = [0.9, 0.3, 0.2]) translate([-1, 0.8, 0]) sphere(0.6);
  material(color = [0.2, 0.5, 0.9]) translate([0, 0.8, 0]) box(0.8);
  material(color = [0.3, 0.8, 0.3]) translate([1, 0.8, 0]) torus(0.4, 0.15);
  translate([0, 0.1, 0]) box([3, 0.2, 1]);
}
translate([-2, 0.7, -1.5]) twist(90) box([0.4, 1.4, 0.4]);
translate([2, 0.5, -1.5]) smooth_intersection(0.1) { box(0.8); sphere(0.55); }
for (i = [0:5]) translate([-2.5 + i, 0.2, 1.5]) sphere(0.2);
)");
    const Pair p = render_both(c->cs);
    INFO("psnr " << psnr(p.accel, p.base));
    CHECK(psnr(p.accel, p.base) >= 45.0);
    CHECK(p.sa.distance_points + p.sa.shading_points < p.sb.distance_points + p.sb.shading_points);
}

TEST_CASE("accel: a fractal's distance estimate, far above the distance away from it, matches the baseline", "[accel]") {
    // 0.5 log(r) r / dr: a distance near the set only (at r = 100 it reads 230). Its
    // intervals are unknown (the escape loop overflows): a big cell's centre value must not
    // prove the cell empty, which left the whole picture background.
    auto c = test::compile_text(R"(
camera(position = [0, 1.5, 3], target = [0, 0, 0], fov = 40);
render(width = 80, height = 60);
field (p) -> { var z = p; var dr = 1.0; var r = length(z);
  for (i = [0 : 5]) { if (r < 2) { dr = pow(r, 7) * 8 * dr + 1; z = pow(r, 8) * normalize(z) + p; r = length(z); } }
  0.5 * log(max(r, 1e-6)) * r / dr };
)");
    const Pair p = render_both(c->cs);
    INFO("psnr " << psnr(p.accel, p.base));
    CHECK(psnr(p.accel, p.base) >= 45.0);
    const Image black(80, 60, 3);
    CHECK(psnr(p.accel, black) < 30.0);  // the bulb is there
}

TEST_CASE("accel: the examples match the baseline", "[accel][examples]") {
    // At a quarter of the benchmark's 640 x 360, with each example's own samples (at most 2):
    // with one sample, pixels at box edges and grazing rays are coin flips that differ
    // between any two ways of stepping (the hit point moves within the hit threshold, and
    // an edge's normal blends its faces), so single-sample PSNR says little.
    for (const char* name : {"three-tori", "csg-tori", "seasquid", "recursive1", "lattice", "gyroid-ball", "showcase"}) {
        SourceManager sm;
        const std::string path = std::string(SDFC_SOURCE_DIR) + "/examples/" + name + ".sdf";
        CompiledScene cs = compile_scene(load_scene(sm, path));
        cs.render.width = 320;
        cs.render.height = 180;
        cs.render.samples = std::min(cs.render.samples, 2);
        const Pair p = render_both(cs);
        INFO(name << ": psnr " << psnr(p.accel, p.base));
        CHECK(psnr(p.accel, p.base) >= 45.0);
        CHECK(p.sa.distance_points < p.sb.distance_points);
    }
}

TEST_CASE("accel: 3,600 floating spheres match the baseline, their tree capped at a node per 16 samples", "[accel]") {
    // No floor: rays are clipped to the grid's box and each tile's pre-march begins where
    // its cone reaches it (rules.h sdf_premarch_begin).
    auto c = test::compile_text(grid_scene(60, 160, 90, false));
    const Pair p = render_both(c->cs);
    INFO("psnr " << psnr(p.accel, p.base) << " leaves " << p.sa.tree_leaves);
    CHECK(psnr(p.accel, p.base) >= 45.0);
    // 14,400 samples: the floor of 4,096 nodes holds (without the cap: many more leaves).
    CHECK(p.sa.tree_leaves > 1000);
    CHECK(p.sa.tree_leaves <= 4096);
    CHECK(p.sa.distance_instructions * 4 <= p.sb.distance_instructions);
}

TEST_CASE("accel: a thin layer of shapes lies above the tree root's midplane, not across it", "[accel]") {
    // 3,600 floating spheres 0.13 high over 10 x 10: on y the root is centred just below them
    // (each cell's lower face then holds the layer), and it still covers the box and its pad.
    RenderOptions ro;
    auto thin = test::compile_text(grid_scene(60, 160, 90, false));
    const cpu::Frame f = cpu::make_frame(thin->cs, ro);
    glm::vec3 lo, hi;
    REQUIRE(f.clip);
    bool layer = false;
    REQUIRE(cpu::tree_root(f, thin->cs, ro, lo, hi, &layer));
    CHECK(layer);  // (the tree then gets two thirds of the node budget)
    const float mid = 0.5f * (lo.y + hi.y);
    INFO("box y " << f.lo.y << " .. " << f.hi.y << ", root y " << lo.y << " .. " << hi.y);
    CHECK(mid < f.lo.y);
    CHECK(mid > f.lo.y - 0.05f);
    CHECK(lo.y <= f.lo.y - 0.25f);
    CHECK(hi.y >= f.hi.y + 0.25f);
    CHECK(0.5f * (lo.x + hi.x) == Approx(0.5f * (f.lo.x + f.hi.x)).margin(1e-4));  // x and z are not thin
    CHECK(0.5f * (lo.z + hi.z) == Approx(0.5f * (f.lo.z + f.hi.z)).margin(1e-4));
    // 64 spheres 1.0 high over 10 x 10 are not a thin layer: the root stays centred on the box.
    auto thick = test::compile_text(grid_scene(8, 160, 90, false));
    const cpu::Frame g = cpu::make_frame(thick->cs, ro);
    REQUIRE(cpu::tree_root(g, thick->cs, ro, lo, hi, &layer));
    CHECK_FALSE(layer);
    CHECK(0.5f * (lo.y + hi.y) == Approx(0.5f * (g.lo.y + g.hi.y)).margin(1e-4));
}

TEST_CASE("accel: under a thin layer the tree splits no cell proven empty", "[accel]") {
    // 3,600 floating spheres (tests above): the air just over the layer keeps nearly every
    // sphere within reach in its tapes, so under a thin layer the node budget goes to the
    // cells that may hold surface (tape_tree.cpp kTreeThinNear). Elsewhere empty cells near
    // the surface are split too (kTreeNear), as the same tree built without the layer shows.
    auto c = test::compile_text(grid_scene(60, 160, 90, false));
    RenderOptions ro;
    const cpu::Frame f = cpu::make_frame(c->cs, ro);
    glm::vec3 lo, hi;
    bool layer = false;
    REQUIRE(cpu::tree_root(f, c->cs, ro, lo, hi, &layer));
    REQUIRE(layer);
    const Tape full = Tape::from(c->cs.distance, 0);
    IntervalEvaluator iv(full.num_regs, full.choices);
    // The split nodes whose box the whole program's interval proves empty (a tape simplified
    // for a box around it is never less sure).
    auto empty_splits = [&](const cpu::TapeTree& T) {
        int n = 0;
        for (size_t i = 1; i < T.nodes.size(); ++i) {
            if (T.nodes[i].child & cpu::TapeTree::kLeafBit) continue;
            const auto& B = T.boxes_[i];
            iv.eval(full, &B.lo[0], &B.hi[0], &B.lo[1], &B.hi[1], &B.lo[2], &B.hi[2], 1);
            n += iv.result(0).lo > 0.0f;
        }
        return n;
    };
    cpu::TapeTree thin, plain;
    cpu::build_tree(thin, c->cs.distance, lo, hi, 0.0f, true, 160 * 90, true);
    cpu::build_tree(plain, c->cs.distance, lo, hi, 0.0f, true, 160 * 90, false);
    REQUIRE(thin.active);
    REQUIRE(plain.active);
    INFO("nodes " << thin.nodes.size() << " / " << plain.nodes.size());
    CHECK(empty_splits(thin) == 0);
    CHECK(empty_splits(plain) > 0);
}

TEST_CASE("accel: a raw field's tree splits cells however short their tapes, and its rays jump more", "[accel]") {
    // The same floating spheres marched as a raw field (as a .vm model is: no distance
    // bound, sign-change steps) and as a distance: the raw field's cells go on splitting
    // below the 64-instruction tapes where a distance's stop, so more of its marches'
    // small steps become jumps over empty cells.
    const auto [d, r] = render_distance_and_raw(grid_scene(12, 160, 90, false));
    const double tape_d = double(d.sa.distance_instructions) / double(d.sa.distance_points);
    const double tape_r = double(r.sa.distance_instructions) / double(r.sa.distance_points);
    INFO("leaves " << d.sa.tree_leaves << " / " << r.sa.tree_leaves << ", tape " << tape_d << " / " << tape_r << ", skips "
                   << d.sa.skips << " / " << r.sa.skips << ", points " << r.sa.distance_points << " / " << r.sb.distance_points
                   << ", psnr " << psnr(r.accel, r.base));
    CHECK(r.sa.tree_leaves > 2 * d.sa.tree_leaves);
    CHECK(tape_r < 0.5 * tape_d);
    CHECK(r.sa.distance_points < r.sb.distance_points);
    CHECK(psnr(r.accel, r.base) >= 40.0);
}

TEST_CASE("accel: a raw field's shadow rays stop where the rest of their way is proven empty", "[accel]") {
    // Floating spheres and one high above a corner (the scene's box, where rays are clipped,
    // reaches up to it): marked raw, the shadow rays toward the light end where the tree
    // proves the rest of their segments empty. The picture is the one drawn without the
    // cuts (36.6 dB from the baseline, which raw marching's missed specks of the small
    // sphere cost, with or without them: the two are 32.0 and 32.3 dB from the same scene
    // drawn as a distance, 31.8 and 32.2 dB before rules.h's secant steps). (A distance's
    // shadow rays are never cut: they jump or step on distances.)
    const auto [d, r] = render_distance_and_raw(grid_scene(12, 160, 90, false) + "translate([5, 3, 5]) sphere(0.3);\n");
    INFO("shadow cuts " << r.sa.shadow_cuts << ", skips " << r.sa.skips << ", psnr " << psnr(r.accel, r.base));
    CHECK(r.sa.shadow_cuts > 0);
    CHECK(d.sa.shadow_cuts == 0);
    CHECK(psnr(r.accel, r.base) >= 36.0);
}

TEST_CASE("accel: a raw field's rays jump through cells whose surface their way is proven to miss", "[accel]") {
    // Floating spheres marched as a raw field: a cell with surface in it is not empty, but
    // the interval of its tape over the box around a ray's way through it can still be
    // positive (a shadow ray leaving a sphere, a ray passing beside one). Those rays jump
    // as over an empty cell instead of stepping a pixel at a time (segment_bounds). Never
    // for a distance, whose steps are already as long as its bound.
    const auto [d, r] = render_distance_and_raw(grid_scene(12, 160, 90, false));
    const double shadows = double(r.sa.distance_points_by[RenderStats::kShadows]);
    INFO("segment skips " << r.sa.segment_skips << " of " << r.sa.skips << ", shadow points " << shadows << ", rays "
                          << r.sa.distance_points_by[RenderStats::kRays] << ", psnr " << psnr(r.accel, r.base));
    CHECK(r.sa.segment_skips > 0);
    CHECK(r.sa.segment_skips <= r.sa.skips);
    CHECK(d.sa.segment_skips == 0);
    CHECK(psnr(r.accel, r.base) >= 40.0);
}

TEST_CASE("accel: a raw field's tiles of camera rays cross empty cells together", "[accel]") {
    // Spheres on a floor seen from above, marked raw: the tiles begin at the camera (floor
    // planes: no box to clip to) and cross the empty space above the spheres together, so
    // their rays jump less; the picture stays the baseline's. (A distance's tiles pre-march
    // on distances instead.) The baseline marches the raw field sample by sample: 16 of
    // its 14,400 pixels differ by more than 8 levels in 255 (38.3 dB; 12 pixels and 41.1 dB
    // before rays jumped through cells on their segments' bounds), shadow specks where
    // shadow rays graze the seams of spheres and floor, thinner than a step, in both ways.
    const auto [d, r] = render_distance_and_raw(grid_scene(12, 160, 90, true));
    INFO("tile skips " << r.sa.tile_skips << ", skips " << r.sa.skips << ", psnr " << psnr(r.accel, r.base));
    CHECK(r.sa.tile_skips > 0);
    CHECK(d.sa.tile_skips == 0);
    CHECK(psnr(r.accel, r.base) >= 38.0);
}

TEST_CASE("accel: a raw field's sheet of zero thickness (max(a, -a)) is proven empty, not marched through", "[accel]") {
    // 36 balls and, behind them, the sheet z = -0.7 that a union with max(a, -a) = |a|
    // leaves (as coincident faces of a CSG model do): the field touches 0 there but never
    // goes below, so the marches see no surface. The tree folds max(a, -a) into abs(a), whose
    // interval is not negative: the sheet's cells count as empty (tape_tree.hpp kSheet), the
    // rays jump over them, and the picture is the balls' alone.
    std::string balls = "x var-x\ny var-y\nz var-z\nz2 square z\nrad const 0.1\n";
    for (int i = 0; i < 36; ++i) {
        const std::string n = std::to_string(i);
        balls += "cx" + n + " const " + std::to_string(-0.75 + 0.3 * (i % 6)) + "\ncy" + n + " const " + std::to_string(-0.75 + 0.3 * (i / 6)) +
                 "\ndx" + n + " sub x cx" + n + "\ndy" + n + " sub y cy" + n + "\nxx" + n + " square dx" + n + "\nyy" + n + " square dy" + n +
                 "\ns" + n + " add xx" + n + " yy" + n + "\nt" + n + " add s" + n + " z2\nr" + n + " sqrt t" + n + "\nb" + n + " sub r" + n + " rad\n" +
                 "u" + n + " min b" + n + " " + (i == 0 ? "b0" : "u" + std::to_string(i - 1)) + "\n";
    }
    const std::string sheet = balls + "c const 0.7\na add z c\nna neg a\nsh max a na\no min u35 sh\n";
    SourceManager sm;
    CompiledScene with = compile_scene(load_vm(sm, sm.add("sheet.vm", sheet)));
    CompiledScene without = compile_scene(load_vm(sm, sm.add("balls.vm", balls)));
    for (CompiledScene* cs : {&with, &without}) cs->render.width = 160, cs->render.height = 120;
    cpu::TapeTree T;
    cpu::build_tree(T, with.distance, glm::vec3(-1), glm::vec3(1), 0.0f, false, 160 * 120);
    REQUIRE(T.active);
    for (const glm::vec3 p : {glm::vec3(0.8f, 0.8f, -0.7f), glm::vec3(-0.9f, 0.1f, -0.7f), glm::vec3(0.0f, -0.85f, -0.7f)}) {
        const cpu::TapeTree::Leaf& L = T.leaves[T.locate(p.x, p.y, p.z)];
        INFO("leaf at " << p.x << ", " << p.y << ", " << p.z << ": [" << L.ivlo << ", " << L.ivhi << "]");
        CHECK(L.ivlo > 0.0f);
    }
    RenderOptions ro;
    ro.threads = 2;
    RenderStats sw, so;
    const Image a = render(with, ro, &sw), b = render(without, ro, &so);
    INFO("points " << sw.distance_points << " / " << so.distance_points << ", skips " << sw.skips << " / " << so.skips << ", psnr "
                   << psnr(a, b));
    CHECK(psnr(a, b) >= 45.0);
    CHECK(sw.distance_points < so.distance_points * 5 / 4);
}

TEST_CASE("accel: a leaf's ropes lead to its neighbours, and lookups through them find the point's leaf", "[accel]") {
    // A raw field's deep tree over 144 spheres: every leaf's rope across each face is a node
    // at least as big as the leaf whose box touches that face and covers it (or the root
    // past the root's faces), and a point just past a face, found from the leaf, lands in
    // a leaf that holds it: the one a lookup from the root finds.
    auto c = test::compile_text(grid_scene(12, 160, 90, false));
    cpu::TapeTree T;
    const glm::vec3 lo(-6, -1, -6), hi(6, 1, 6);
    cpu::build_tree(T, c->cs.distance, lo, hi, 0.0f, false, 160 * 90);
    REQUIRE(T.active);
    REQUIRE(T.leaves.size() > 1000);
    size_t inner = 0, outer = 0, looked = 0, found = 0;
    uint32_t rng = 12345;
    auto uniform = [&] {
        rng = rng * 1664525u + 1013904223u;
        return float(rng >> 8) / float(1 << 24);
    };
    for (uint32_t l = 1; l < T.leaves.size(); ++l) {
        const cpu::TapeTree::Leaf& L = T.leaves[l];
        if (!(L.lo[0] <= L.hi[0])) continue;
        for (int f = 0; f < 6; ++f) {
            const int a = f >> 1;
            const bool plus = f & 1;
            const uint32_t m = T.rope(l, f);
            const float face = plus ? L.hi[a] : L.lo[a];
            if (m == 0) {
                CHECK(face == (plus ? hi[a] : lo[a]));
                ++outer;
                continue;
            }
            const cpu::TapeTree::NodeBox& B = T.boxes_[m];
            bool ok = (plus ? B.lo[a] : B.hi[a]) == face && B.hi[a] - B.lo[a] >= L.hi[a] - L.lo[a];
            for (int b = 0; b < 3; ++b)
                if (b != a) ok = ok && B.lo[b] <= L.lo[b] && B.hi[b] >= L.hi[b];
            if (!ok) FAIL_CHECK("leaf " << l << " face " << f << ": rope " << m << " is not its neighbour");
            ++inner;
            // A point past the face (up to two leaf sizes), elsewhere random in the leaf.
            float p[3];
            for (int b = 0; b < 3; ++b) p[b] = L.lo[b] + uniform() * (L.hi[b] - L.lo[b]);
            const float past = (0.01f + 2.0f * uniform()) * (L.hi[a] - L.lo[a]);
            p[a] = plus ? face + past : face - past;
            const uint32_t id = T.locate_from(l, p[0], p[1], p[2]);
            const cpu::TapeTree::Leaf& R = T.leaves[id];
            const bool holds = p[0] >= R.lo[0] && p[0] <= R.hi[0] && p[1] >= R.lo[1] && p[1] <= R.hi[1] && p[2] >= R.lo[2] &&
                               p[2] <= R.hi[2];
            const bool in_root = p[a] >= lo[a] && p[a] <= hi[a];
            if (in_root) {
                CHECK(holds);
                ++looked;
                found += id == T.locate(p[0], p[1], p[2]);
            } else {
                CHECK(id == 0);
            }
        }
    }
    INFO("ropes to neighbours " << inner << ", to the outside " << outer << ", lookups " << looked << ", as from the root "
                                 << found);
    CHECK(inner > 6 * 1000);
    CHECK(outer > 0);
    CHECK(looked > inner * 9 / 10);
    CHECK(found == looked);  // (random points: none on a cell's face, which could go to either side)
}

TEST_CASE("accel: a box is proven empty only where every leaf it meets is", "[accel]") {
    // 144 spheres of radius 0.4 c (c = 10 / 12) centred at height 0.3 c, in a root box from
    // -6 to 6 (y: -1 to 1); the tree of a raw field (leaves as small as the surface asks).
    auto c = test::compile_text(grid_scene(12, 160, 90, false));
    cpu::TapeTree T;
    cpu::build_tree(T, c->cs.distance, glm::vec3(-6, -1, -6), glm::vec3(6, 1, 6), 0.0f, false, 160 * 90);
    REQUIRE(T.active);
    const float cell = 10.0f / 12.0f, top = 0.7f * cell;  // the spheres' tops
    const float x = 0.5f * cell;  // a sphere's centre: (x, 0.3 c, x)
    CHECK(T.all_empty(glm::vec3(-0.4f, 0.8f, -0.4f), glm::vec3(x + 0.4f, 0.9f, x + 0.4f)));  // over the spheres
    CHECK(T.all_empty(glm::vec3(5.3f, -0.5f, 5.3f), glm::vec3(5.6f, 0.5f, 5.6f)));            // past the grid's edge
    CHECK_FALSE(T.all_empty(glm::vec3(x - 0.1f, top - 0.05f, x - 0.1f), glm::vec3(x + 0.1f, top + 0.2f, x + 0.1f)));  // a top
    CHECK_FALSE(T.all_empty(glm::vec3(-0.4f, 0.8f, -0.4f), glm::vec3(x + 0.4f, 1.1f, x + 0.4f)));  // past the root's top
    CHECK_FALSE(T.all_empty(glm::vec3(NAN, 0.9f, 0), glm::vec3(0, 0.95f, 0)));
}

namespace {
// Checks Leaf::up and NodeBox::elo of T against brute force; returns the empty leaves and
// how many of them have a bigger empty box.
std::pair<size_t, size_t> check_empty_ancestors(const cpu::TapeTree& T) {
    // elo by brute force: the least ivlo of the leaves under each node (leaves' nodes climbed
    // to the root), -inf where any of them is not empty.
    std::vector<float> elo(T.nodes.size(), INFINITY);
    for (uint32_t l = 1; l < T.leaves.size(); ++l) {
        const float v = T.leaves[l].ivlo > 0.0f ? T.leaves[l].ivlo : -INFINITY;
        for (uint32_t n = T.leaves[l].node;; n = T.boxes_[n].parent) {
            elo[n] = std::min(elo[n], v);
            if (n == 0) break;
        }
    }
    for (size_t n = 0; n < T.nodes.size(); ++n)
        if (T.boxes_[n].elo != (elo[n] > 0.0f ? elo[n] : -INFINITY)) FAIL_CHECK("node " << n << ": elo " << T.boxes_[n].elo);
    size_t empty_leaves = 0, bigger = 0;
    for (uint32_t l = 1; l < T.leaves.size(); ++l) {
        const cpu::TapeTree::Leaf& L = T.leaves[l];
        if (!(L.ivlo > 0.0f)) {
            CHECK(L.up == L.node);
            continue;
        }
        ++empty_leaves;
        const cpu::TapeTree::NodeBox& U = T.boxes_[L.up];
        bool ok = U.empty() && U.elo <= L.ivlo && (L.up == 0 || !T.boxes_[U.parent].empty());
        for (int a = 0; a < 3; ++a) ok = ok && U.lo[a] <= L.lo[a] && U.hi[a] >= L.hi[a];
        for (uint32_t n = L.node; n != L.up && ok; n = T.boxes_[n].parent) ok = n != 0 && T.boxes_[n].empty();
        if (!ok) FAIL_CHECK("leaf " << l << ": up " << L.up << " is not its biggest empty ancestor");
        bigger += L.up != L.node;
    }
    return {empty_leaves, bigger};
}
}  // namespace

TEST_CASE("accel: an empty leaf's biggest empty ancestor, and every node's least lower bound", "[accel]") {
    SECTION("a raw field's tree: the grid of spheres without its floor") {
        auto c = test::compile_text(grid_scene(12, 160, 90, false));
        cpu::TapeTree T;
        cpu::build_tree(T, c->cs.distance, glm::vec3(-6, -1, -6), glm::vec3(6, 1, 6), 0.0f, false, 160 * 90);
        REQUIRE(T.active);
        const auto [empty_leaves, bigger] = check_empty_ancestors(T);
        INFO("empty leaves " << empty_leaves << ", with a bigger empty box " << bigger);
        CHECK(empty_leaves > 1000);
    }
    SECTION("recursive1's sponges: empty cells near the surface split into empty children") {
        SourceManager sm;
        CompiledScene cs = compile_scene(load_scene(sm, std::string(SDFC_SOURCE_DIR) + "/examples/recursive1.sdf"));
        cpu::TapeTree T;
        cpu::build_tree(T, cs.distance, glm::vec3(-3.5f, -1.2f, -3.5f), glm::vec3(3.5f, 1.5f, 2.5f), 0.0f, true, 320 * 180);
        REQUIRE(T.active);
        const auto [empty_leaves, bigger] = check_empty_ancestors(T);
        INFO("empty leaves " << empty_leaves << ", with a bigger empty box " << bigger);
        CHECK(empty_leaves > 100);
        CHECK(bigger > empty_leaves / 8);  // (measured: 246 of 1,075)
    }
}

TEST_CASE("accel: identical pixels for any thread count, with the tree", "[accel][determinism]") {
    auto c = test::compile_text(grid_scene(9, 96, 64));
    RenderOptions ro;
    ro.reuse_tree = false;  // each render builds its tree with its own thread count
    ro.threads = 1;
    RenderStats s1;
    const Image a = render(c->cs, ro, &s1);
    REQUIRE(s1.tree_leaves > 0);
    for (int t : {2, 3}) {
        ro.threads = t;
        RenderStats st;
        const Image b = render(c->cs, ro, &st);
        CHECK(b.pixels == a.pixels);
        CHECK(st.distance_points == s1.distance_points);
        CHECK(st.tree_leaves == s1.tree_leaves);
    }
}

TEST_CASE("accel: a render takes the tree the render before kept only when it would build the same one", "[accel][reuse]") {
    cpu::forget_tree();
    RenderOptions ro;
    ro.threads = 2;
    RenderStats s1, s2, s3, s4, s5;
    Image first(1, 1, 3);
    {
        auto c1 = test::compile_text(grid_scene(9, 96, 64));
        first = render(c1->cs, ro, &s1);
        CHECK_FALSE(s1.tree_reused);
        REQUIRE(s1.tree_leaves > 0);
    }  // (the program the kept tree was built from is gone)
    auto c2 = test::compile_text(grid_scene(9, 96, 64));
    const Image again = render(c2->cs, ro, &s2);
    CHECK(s2.tree_reused);
    CHECK(s2.interval_boxes == 0);
    CHECK(again.pixels == first.pixels);
    CHECK(s2.distance_points == s1.distance_points);
    CHECK(s2.tree_leaves == s1.tree_leaves);
    // Other lights and materials: the same distance program, the same tree.
    auto lit = test::compile_text("light(position = [-6, 10, 4], intensity = 80);\n" + grid_scene(9, 96, 64));
    render(lit->cs, ro, &s3);
    CHECK(s3.tree_reused);
    // Another picture size (the tree's budgets) or another scene: a tree of its own.
    c2->cs.render.width = 80;
    render(c2->cs, ro, &s4);
    CHECK_FALSE(s4.tree_reused);
    auto other = test::compile_text(grid_scene(8, 80, 64));
    render(other->cs, ro, &s5);
    CHECK_FALSE(s5.tree_reused);
    // Off: built again, the same pixels.
    ro.reuse_tree = false;
    RenderStats s6;
    auto c3 = test::compile_text(grid_scene(9, 96, 64));
    const Image fresh = render(c3->cs, ro, &s6);
    CHECK_FALSE(s6.tree_reused);
    CHECK(fresh.pixels == first.pixels);
    cpu::forget_tree();
}

TEST_CASE("accel: progress is reported, last with every tile done", "[accel][progress]") {
    auto c = test::compile_text(grid_scene(4, 64, 48));
    RenderOptions ro;
    ro.threads = 2;
    std::mutex m;
    std::vector<RenderProgress> seen;
    std::atomic<int> concurrent{0}, overlap{0};
    ro.progress = [&](const RenderProgress& p) {
        if (concurrent.fetch_add(1) != 0) overlap.fetch_add(1);
        {
            std::lock_guard<std::mutex> l(m);
            seen.push_back(p);
        }
        concurrent.fetch_sub(1);
    };
    render(c->cs, ro);
    REQUIRE(!seen.empty());
    CHECK(overlap.load() == 0);
    CHECK(seen.back().tiles_done == seen.back().tiles_total);
    CHECK(seen.back().tiles_total == ((64 + 15) / 16) * ((48 + 15) / 16));
    for (const RenderProgress& p : seen) {
        CHECK(p.tiles_done <= p.tiles_total);
        CHECK(p.elapsed_s >= 0.0);
    }
}

TEST_CASE("accel: a floor plane clips rays like a bounding box", "[accel][clip]") {
    auto c = test::compile_text(R"(
camera(position = [0, 2, 6], target = [0, 0.5, 0], fov = 45);
light(direction = [-0.3, -1, -0.5], intensity = 1);
render(width = 160, height = 90);
material(color = [0.8, 0.8, 0.8]) plane([0, 2, 0], -0.5);
translate([0, 0.5, 0]) sphere(0.8);
)");
    // The plane y <= -0.5 as a half-space (unit normal), the sphere in the box.
    REQUIRE(c->cs.half_spaces.size() == 1);
    CHECK(c->cs.half_spaces[0].y == Approx(1.0f));
    CHECK(c->cs.half_spaces[0].w == Approx(-0.5f));
    CHECK(c->cs.solid_bounds.lo.y == Approx(-0.3f));
    CHECK(c->cs.solid_bounds.hi.x == Approx(0.8f));
    const Pair p = render_both(c->cs);
    INFO("psnr " << psnr(p.accel, p.base));
    CHECK(psnr(p.accel, p.base) >= 45.0);
    // Rays into the sky and shadow rays leaving the scene end at once.
    INFO("rays " << p.sa.distance_points_by[RenderStats::kRays] << " / " << p.sb.distance_points_by[RenderStats::kRays]);
    CHECK(p.sa.distance_points_by[RenderStats::kRays] * 2 < p.sb.distance_points_by[RenderStats::kRays]);
    CHECK(p.sa.distance_points_by[RenderStats::kShadows] * 2 < p.sb.distance_points_by[RenderStats::kShadows]);
    // Not with an unbounded shape beside the plane.
    auto g = test::compile_text("plane(); gyroid(1, 0.1);");
    CHECK(g->cs.half_spaces.empty());
}
