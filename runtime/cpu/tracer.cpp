// The CPU sphere tracer. Design (all per tile, all batched through the 64-lane Evaluator):
//
//  * Primary rays: `samples` per pixel on a Hammersley pattern ((i+0.5)/S, radical_inverse(i)
//    + 0.5/S), the same pattern in every pixel, reconstructed with a box filter over the pixel
//    (equal weights). With aa == "cone", one cone per pixel instead (Hart's cone tracing,
//    below), and `samples` is ignored.
//  * Marching: a ray hits when d < epsilon * max(t, 1) (t = path length from the eye, so the
//    tolerance grows with distance like the pixel footprint, but never below epsilon); it
//    misses when t passes max_distance or the scene's bounding box. A ray that runs out of
//    max_steps counts as a hit if it is within one pixel footprint of the surface, else a
//    miss. NaN distances end the ray as a miss, +inf steps to the end, -inf is a hit. A hit
//    point moves on by its last distance d (still outside for a 1-Lipschitz bound).
//  * Normals: tetrahedron technique, n = sum_k k * f(p + e*k) over k in {(1,-1,-1), (-1,-1,1),
//    (-1,1,-1), (1,1,1)}, e = max(epsilon * max(t, 1), 2e-5 * (1 + |p|)).
//  * Shading (Blinn-Phong, not energy normalised):
//        emission + albedo * ambient * ao
//        + sum_lights  colour * intensity * falloff * shadow * (albedo * max(N.L, 0)
//                      + specular * max(N.H, 0)^shininess)              (when N.L > 0)
//    falloff = 1 / distance^2 for point lights, 1 for directional lights.
//  * Shadows: hard (a march toward the light, any hit = 0) when radius == 0, else soft:
//    Quilez's penumbra estimate with the closest-approach refinement (h, previous h) and the
//    inner/outer-penumbra form: res = min(d_closest / (w * t)), marching through occluders,
//    vis = 0.25 (1 + res)^2 (2 - res) for res in [-1, 1]. w = radius / distance for point
//    lights, w = radius (tangent of the angular radius) for directional ones. Soft shadow
//    rays are over-relaxed too, but only where d >= 4 w t (far from any penumbra).
//  * Ambient occlusion: 5 taps along the normal at h = 0.01 .. 0.13 (world units),
//    ao = clamp(1 - 3 * sum max(h - d(p + n h), 0) * 0.95^i, 0, 1) (Quilez); it scales the
//    ambient term only.
//  * Reflection/refraction, iterative (a wavefront of ray generations, not recursion), at
//    most max_bounces generations after the primary one. At a surface with weight W:
//    local shading gets W (1 - reflect)(1 - transparency), the mirror ray W * reflect, and
//    the glass part W (1 - reflect) transparency splits by Schlick's Fresnel F into a
//    reflected ray (F) and a refracted one ((1 - F) * colour, i.e. tinted glass). Inside a
//    solid the ray marches on -d; at the exit it refracts out (1 - F) and reflects back in
//    (F), or reflects totally. When no bounce is left the surface is shaded as opaque
//    (and a ray inside glass is dropped). Rays below 1e-3 of a sample's weight are dropped.
//  * Cone tracing (aa == "cone"): the cone's radius is the pixel footprint r(t). Where the
//    ray passes an edge (d < r without hitting), the closest approach (smallest d/r) is
//    recorded as a partial hit of coverage 1 - d/r; up to 4 such layers are composited front
//    to back, then the final hit (or the background) gets the remaining weight.
//  * AOVs: depth = first-hit distance (max_distance for misses; per pixel the minimum over
//    samples), normal = unit world normal of the first hit (sample average, renormalised),
//    steps = average primary-ray step count.
//  * Over-relaxed sphere tracing (Keinert et al. 2014, omega = 1.5 falling back to 1 when
//    consecutive unbounding spheres stop overlapping) for camera, secondary and hard shadow
//    rays: fewer steps, same hits for any 1-Lipschitz bound.
//  * Raw fields (CompiledScene::raw_field, .vm models, no distance bound): see march_raw();
//    sign-change marching with bisection, hard shadows only, no AO, no cone tracing.
//  * 2D models (CompiledScene::is_2d): W x H samples over [-1, 1]^2 including both ends,
//    row 0 at y = +1, white where the field is < 0, black elsewhere.
// FP exceptions are never unmasked here, so GCC may if-convert float compares: the lane
// update loops below vectorise only with this.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include "runtime/cpu/tracer.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <deque>
#include <queue>
#include <stdexcept>

#include "compiler/render/camera.hpp"
#include "runtime/eval/interval.hpp"
#include "runtime/eval/vm.hpp"


namespace sdfc {

const std::vector<std::string>& known_aovs() {
    static const std::vector<std::string> k{"depth", "normal", "steps"};
    return k;
}

namespace {
struct Dbg { std::atomic<uint64_t> pts[2][4]{}, ins[2][4]{}; ~Dbg() { if (getenv("DBG")) for (int z = 0; z < 2; ++z) for (int k = 0; k < 4; ++k) fprintf(stderr, "leaf0=%d kind=%d points=%lu instr=%lu\n", z, k, (unsigned long)pts[z][k], (unsigned long)ins[z][k]); } } g_dbg;

constexpr int kConeEvents = 4;
constexpr int kAoTaps = 5;
constexpr float kMinWeight = 1e-3f;
constexpr float kRelax = 1.5f;  // over-relaxed sphere tracing factor (Keinert et al. 2014)
constexpr float kRelaxNear = 8.0f;  // ... but plain steps where d < this many hit thresholds
constexpr float kSoftRelaxFar = 4.0f;  // soft shadows: over-relaxed only where d >= this x the cone width
constexpr int kMatOut = kMatChannels;  // material channels after the distance output
constexpr int kWindow = 128;        // rays in flight per worker (a multiple of kBatch)
static_assert(kWindow % kBatch == 0);

// Rays (or hit points) in structure-of-arrays form. For a hit set, `o` is the hit point and
// `t0` the path length from the eye to it.
struct RaySet {
    std::vector<float> ox, oy, oz, dx, dy, dz, tmin, tmax, t0, wr, wg, wb;
    std::vector<uint32_t> prim;  // primary sample index within the tile
    std::vector<uint8_t> inside;
    size_t size() const { return n_; }
    void clear() { n_ = 0; }
    // Arrays are only grown, never shrunk: pushing is a bounds check and twelve stores.
    void push(const glm::vec3& o, const glm::vec3& d, float t_min, float t_max, float path, const glm::vec3& w, uint32_t p,
              bool in) {
        if (n_ == ox.size()) grow();
        const size_t i = n_++;
        ox[i] = o.x, oy[i] = o.y, oz[i] = o.z;
        dx[i] = d.x, dy[i] = d.y, dz[i] = d.z;
        tmin[i] = t_min, tmax[i] = t_max, t0[i] = path;
        wr[i] = w.x, wg[i] = w.y, wb[i] = w.z;
        prim[i] = p;
        inside[i] = in ? 1 : 0;
    }
    glm::vec3 o(size_t i) const { return {ox[i], oy[i], oz[i]}; }
    glm::vec3 d(size_t i) const { return {dx[i], dy[i], dz[i]}; }
    glm::vec3 w(size_t i) const { return {wr[i], wg[i], wb[i]}; }

private:
    size_t n_ = 0;
    void grow() {
        const size_t cap = std::max<size_t>(256, ox.size() * 2);
        for (auto* v : {&ox, &oy, &oz, &dx, &dy, &dz, &tmin, &tmax, &t0, &wr, &wg, &wb}) v->resize(cap);
        prim.resize(cap);
        inside.resize(cap);
    }
};

float radical_inverse2(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x55555555u) << 1) | ((i & 0xAAAAAAAAu) >> 1);
    i = ((i & 0x33333333u) << 2) | ((i & 0xCCCCCCCCu) >> 2);
    i = ((i & 0x0F0F0F0Fu) << 4) | ((i & 0xF0F0F0F0u) >> 4);
    i = ((i & 0x00FF00FFu) << 8) | ((i & 0xFF00FF00u) >> 8);
    return static_cast<float>(i) * 2.3283064365386963e-10f;
}

float nonneg(float v) { return v > 0.0f ? (std::isfinite(v) ? v : 1e30f) : 0.0f; }  // NaN -> 0
float clamp01(float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; }
float max3(const glm::vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }
float maxabs3(const glm::vec3& v) { return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z))); }

float schlick(float cos_theta, float ior) {
    float r0 = (ior - 1.0f) / (ior + 1.0f);
    r0 *= r0;
    float m = 1.0f - clamp01(cos_theta);
    float m2 = m * m;
    return r0 + (1.0f - r0) * m2 * m2 * m;
}

// ---------------------------------------------------------------------------------------
// The tape tree: an octree over a root box around the scene, built once per frame before
// the tiles. A cell's 8 children are evaluated as 8 interval lanes with the cell's tape;
// each child gets the tape simplified for its box (runtime/eval/interval.hpp: the same floats as
// the full program at every point of the box) and its interval [ivlo, ivhi]. Leaves keep
// their tapes, concatenated in `code`. Leaf 0 stands for everything outside the root box:
// the full program, never skipped.
//
// Rays locate the leaf of each point (a lane caches its leaf's box), evaluate that leaf's
// tape, and when the leaf's interval proves it empty (no surface: for a 1-Lipschitz bound,
// d >= ivlo > 0 everywhere in it) jump to where they leave the box, plus ivlo.
constexpr int kTreeMaxDepth = 16;
constexpr size_t kTreeLeafTape = 64;      // tapes this short are not split further
constexpr size_t kTreeMinProgram = 128;   // shorter programs get no tree (lookups would cost more)
constexpr size_t kTreePilot = 32;          // after splits worth this many programs ...
constexpr double kTreeUseless = 0.6;      // ... surface cells' tapes this long: no tree
constexpr size_t kTreeMaxNodes = size_t(1) << 20;
constexpr int kTreeMaxStall = 3;          // splits in a row that did not shorten tapes (x 0.9)
constexpr float kTreeNear = 0.25f;        // empty cells are split when the surface is this near (x size)
// Build work budget (instructions interval-evaluated, 8 boxes at a time): a constant, plus
// per program instruction, plus per sample of the image (the evaluations it will save).
constexpr size_t kTreeWorkPerInstr = 64, kTreeWorkBase = size_t(16) << 10, kTreeWorkPerSample = 1;

struct TapeTree {
    static constexpr uint32_t kLeafBit = 0x80000000u;
    struct Node {                 // what a descent reads: 16 bytes
        float c[3] = {0, 0, 0};   // split point: children with x >= c[0] have bit 0 set, ...
        uint32_t child = kLeafBit;  // first of 8 children, or kLeafBit | leaf index
    };
    struct NodeBox {              // what a climb reads
        float lo[3] = {0, 0, 0};
        uint32_t parent = 0;
        float hi[3] = {0, 0, 0};
        uint32_t pad = 0;
        bool holds(float x, float y, float z) const {
            return x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1] && z >= lo[2] && z <= hi[2];
        }
    };
    struct Leaf {
        float lo[3], hi[3];  // the box (leaf 0: empty box, so that lanes always re-locate)
        float ivlo, ivhi;    // the distance over the box
        const Instr* code;   // its tape (in `tapes`), len instructions, output register out
        uint32_t len;
        uint16_t out;
        uint32_t node;       // its node (leaf 0: the root)
    };
    glm::vec3 lo{0}, hi{0};
    std::vector<Node> nodes;
    std::vector<NodeBox> boxes_;
    std::vector<Leaf> leaves;
    std::vector<std::vector<Instr>> tapes;  // [0]: the full program
    uint32_t max_regs = 1;
    uint64_t boxes = 0;
    bool active = false;

    // Leaf 0 only: the full program everywhere.
    void init_full(const Program& p) {
        tapes.assign(1, p.code);
        constexpr float inf = INFINITY;
        leaves.assign(1, Leaf{{inf, inf, inf}, {-inf, -inf, -inf}, -inf, inf, tapes[0].data(), static_cast<uint32_t>(tapes[0].size()),
                              p.outputs.empty() ? uint16_t(0) : p.outputs[0], 0});
        max_regs = std::max<uint32_t>(p.num_regs, 1);
        nodes.clear();
        boxes_.clear();
        active = false;
    }

    uint32_t descend(uint32_t n, float x, float y, float z) const {
        for (;;) {
            const Node& N = nodes[n];
            if (N.child & kLeafBit) return N.child & ~kLeafBit;
            n = N.child + uint32_t(x >= N.c[0]) + 2u * uint32_t(y >= N.c[1]) + 4u * uint32_t(z >= N.c[2]);
        }
    }
    uint32_t locate(float x, float y, float z) const {
        if (!active || !boxes_[0].holds(x, y, z)) return 0;
        return descend(0, x, y, z);
    }
    // The same, starting from leaf `near` (a neighbour is found by climbing a level or two).
    uint32_t locate_from(uint32_t near, float x, float y, float z) const {
        if (!active) return 0;
        uint32_t n = leaves[near].node;
        while (n != 0 && !boxes_[n].holds(x, y, z)) n = boxes_[n].parent;
        if (n == 0 && !boxes_[0].holds(x, y, z)) return 0;
        return descend(n, x, y, z);
    }
};

struct TreeCell {
    glm::vec3 lo{0}, hi{0};
    float ivlo = -INFINITY, ivhi = INFINITY;
    int depth = 0, stall = 0;
    // An empty (or solid) cell that will not be split runs its parent's tape (valid in the
    // parent's box, hence in its own): ref_cell is the parent.
    uint32_t ref_cell = 0xFFFFFFFFu;
    Tape tape;
};

// Empty (ivlo > 0) or solid (ivhi < 0): no surface inside.
bool settled(float ivlo, float ivhi) { return ivlo > 0.0f || ivhi < 0.0f; }
// An empty or solid cell is still split when the surface is within kTreeNear of its size
// (rays, normal and AO taps and soft shadows evaluate there).
bool near_surface(const TreeCell& c) {
    const float size = max3(c.hi - c.lo), d = c.ivlo > 0.0f ? c.ivlo : -c.ivhi;
    return d < kTreeNear * size;
}

bool want_split(const TreeCell& c) {
    if (c.ref_cell != 0xFFFFFFFFu) return false;
    if (c.depth >= kTreeMaxDepth || c.tape.code.size() <= kTreeLeafTape || c.stall >= kTreeMaxStall) return false;
    const float size = max3(c.hi - c.lo);
    if (!(size > 0.0f) || !std::isfinite(size)) return false;
    return !settled(c.ivlo, c.ivhi) || near_surface(c);  // may hold the surface, or unknown (NaN)
}

struct TreeScratch {
    std::unique_ptr<IntervalEvaluator> iv;
    uint32_t regs = 0, choices = 0;
    BatchScratch bs;
    uint64_t boxes = 0;
    std::unique_ptr<Program> vm_regs;  // sizes `vm` (eval_code only)
    std::unique_ptr<Evaluator> vm;
    IntervalEvaluator& get(uint32_t r, uint32_t c) {
        if (!iv || r > regs || c > choices) {
            regs = std::max(regs, r);
            choices = std::max(choices, c);
            iv = std::make_unique<IntervalEvaluator>(regs, choices);
        }
        return *iv;
    }
    Evaluator& point_vm(uint32_t r) {
        if (!vm || r > vm_regs->num_regs) {
            vm.reset();
            vm_regs = std::make_unique<Program>();
            vm_regs->num_regs = std::max<uint32_t>(r, 64);
            vm = std::make_unique<Evaluator>(*vm_regs);
        }
        return *vm;
    }
};

// Builds the tree over [lo, hi] for output 0 of `p` (call inside the render's task arena).
// Best first: the cells worth splitting wait in a queue ordered by tape length x size^2
// (roughly the evaluations a split saves: long tapes, big surfaces), and rounds of up to
// kTreeRound of them are split in parallel until the queue empties or the work budget
// (instructions interval-evaluated) runs out. Deterministic for any thread count.
// `lipschitz`: the program is a 1-Lipschitz distance bound, so a child's interval can be
// tightened with the value at its centre c: d(p) is within |p - c| of d(c). That rescues
// fields whose intervals are weak far away (rotations by an angle that depends on the
// point: twist, bend). The tightened bounds decide splits and rays' jumps (as safe as a
// sphere-tracing step); tape simplification uses the interval choices alone.
void build_tree(TapeTree& T, const Program& p, glm::vec3 lo, glm::vec3 hi, float time, bool lipschitz, size_t samples) {
    constexpr uint32_t kNone = 0xFFFFFFFFu;
    constexpr size_t kTreeRound = 64;
    T.init_full(p);
    T.lo = lo;
    T.hi = hi;
    T.active = true;
    std::deque<TreeCell> cells(1);  // cell i is node i (a deque: growing moves nothing)
    cells[0].lo = lo, cells[0].hi = hi;
    cells[0].tape = Tape::from(p, 0);
    std::vector<uint32_t> first_child(1, kNone);
    std::vector<uint8_t> keep(1, 0);  // the cell's tape is run by settled children
    using Item = std::pair<double, uint32_t>;  // (priority, ~index): ties go to the lower index
    std::priority_queue<Item> queue;
    auto consider = [&](uint32_t i) {
        const TreeCell& c = cells[i];
        if (!want_split(c)) return;
        const double size = max3(c.hi - c.lo);
        const double prio = static_cast<double>(c.tape.code.size()) * size * size * (settled(c.ivlo, c.ivhi) ? 0.25 : 1.0);
        queue.emplace(prio, ~i);
    };
    consider(0);
    tbb::enumerable_thread_specific<TreeScratch> scratch;
    const size_t budget = kTreeWorkBase + kTreeWorkPerInstr * p.code.size() + kTreeWorkPerSample * samples;
    size_t work = 0;
    std::vector<uint32_t> round;
    bool checked = false;
    while (!queue.empty()) {
        // Once the tree is a few levels deep: if the tapes of the cells that may hold the
        // surface are not much shorter than the program (smooth blends, domain repetition:
        // nothing for the intervals to decide), the lookups would cost more than they save.
        if (!checked && work >= kTreePilot * p.code.size()) {
            checked = true;
            size_t n = 0, len = 0;
            for (size_t i = 0; i < cells.size(); ++i)
                if (first_child[i] == kNone && cells[i].ref_cell == kNone && !settled(cells[i].ivlo, cells[i].ivhi))
                    ++n, len += cells[i].tape.code.size();
            if (n > 0 && static_cast<double>(len) > kTreeUseless * static_cast<double>(n) * static_cast<double>(p.code.size())) {
                for (const TreeScratch& s : scratch) T.boxes += s.boxes;
                T.init_full(p);
                return;
            }
        }
        round.clear();
        while (!queue.empty() && round.size() < kTreeRound && cells.size() + 8 * (round.size() + 1) <= kTreeMaxNodes) {
            const uint32_t i = ~queue.top().second;
            const size_t len = cells[i].tape.code.size();
            if (work + len > budget) break;
            queue.pop();
            work += len;
            round.push_back(i);
        }
        if (round.empty()) break;
        const uint32_t base = static_cast<uint32_t>(cells.size());
        cells.resize(cells.size() + 8 * round.size());
        first_child.resize(cells.size(), kNone);
        keep.resize(cells.size(), 0);
        for (size_t q = 0; q < round.size(); ++q) first_child[round[q]] = base + static_cast<uint32_t>(8 * q);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, round.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
            TreeScratch& s = scratch.local();
            for (size_t q = r.begin(); q != r.end(); ++q) {
                const uint32_t i = round[q];
                TreeCell& c = cells[i];
                const uint32_t first = first_child[i];
                const glm::vec3 mid = 0.5f * (c.lo + c.hi);
                float bx[6][kIvLanes];
                for (int k = 0; k < 8; ++k)
                    for (int a = 0; a < 3; ++a) {
                        const bool upper = (k >> a) & 1;
                        bx[2 * a][k] = upper ? mid[a] : c.lo[a];
                        bx[2 * a + 1][k] = upper ? c.hi[a] : mid[a];
                    }
                if (!c.tape.linked) c.tape.link();
                IntervalEvaluator& iv = s.get(c.tape.num_regs, c.tape.choices);
                iv.eval(c.tape, bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], 8, time);
                s.boxes += 8;
                // Children the intervals leave ambiguous: tighten with the centre values (one
                // evaluation of this cell's tape at the 8 centres).
                bool ambiguous = false;
                for (int k = 0; k < 8; ++k) ambiguous |= !settled(iv.result(k).lo, iv.result(k).hi);
                float dc[8];
                std::fill_n(dc, 8, NAN);
                if (lipschitz && ambiguous) {
                    alignas(64) float cx[kBatch], cy[kBatch], cz[kBatch];
                    for (int k = 0; k < 8; ++k) {
                        cx[k] = 0.5f * (bx[0][k] + bx[1][k]);
                        cy[k] = 0.5f * (bx[2][k] + bx[3][k]);
                        cz[k] = 0.5f * (bx[4][k] + bx[5][k]);
                    }
                    Evaluator& vm = s.point_vm(c.tape.num_regs);
                    vm.eval_code(c.tape.code.data(), c.tape.code.size(), cx, cy, cz, 8, time);
                    std::copy_n(vm.reg_data(c.tape.out), 8, dc);
                }
                bool kept = false;
                uint64_t lanes = 0;
                for (int k = 0; k < 8; ++k) {
                    TreeCell& ch = cells[first + static_cast<uint32_t>(k)];
                    ch.lo = glm::vec3(bx[0][k], bx[2][k], bx[4][k]);
                    ch.hi = glm::vec3(bx[1][k], bx[3][k], bx[5][k]);
                    const Interval v = iv.result(k);
                    ch.ivlo = v.lo, ch.ivhi = v.hi;
                    if (std::isfinite(dc[k])) {
                        const float r = 0.5f * glm::length(ch.hi - ch.lo) * (1.0f + 1e-5f) + 1e-6f * (1.0f + std::fabs(dc[k]));
                        if (!(ch.ivlo >= dc[k] - r)) ch.ivlo = dc[k] - r;  // also replaces NaN
                        if (!(ch.ivhi <= dc[k] + r)) ch.ivhi = dc[k] + r;
                    }
                    ch.depth = c.depth + 1;
                    if (settled(ch.ivlo, ch.ivhi) &&
                        !(ch.depth < kTreeMaxDepth && c.tape.code.size() > kTreeLeafTape && near_surface(ch))) {
                        ch.ref_cell = i;  // will not be split: runs this cell's tape
                        kept = true;
                        continue;
                    }
                    lanes |= uint64_t(1) << k;
                }
                size_t sum = 0, nsimp = 0;
                if (lanes) simplify_batch(c.tape, iv.choices(), iv.stride(), lanes, s.bs, true);
                for (int k = 0; k < 8; ++k) {
                    if (!((lanes >> k) & 1)) continue;
                    TreeCell& ch = cells[first + static_cast<uint32_t>(k)];
                    ch.tape.assign(s.bs.code(k), s.bs.len[size_t(k)], s.bs.out[size_t(k)], s.bs.regs[size_t(k)]);
                    sum += ch.tape.code.size();
                    ++nsimp;
                }
                // A split that left the children's tapes about as long as this one (an
                // unprunable field) counts against splitting them again.
                const bool useless = nsimp > 0 && sum * 10 >= c.tape.code.size() * nsimp * 9;
                for (int k = 0; k < 8; ++k) cells[first + static_cast<uint32_t>(k)].stall = useless ? c.stall + 1 : 0;
                keep[i] = kept;
                if (!kept) c.tape = Tape{};  // no longer needed: free it now
            }
        });
        for (size_t q = 0; q < round.size(); ++q)
            for (uint32_t k = 0; k < 8; ++k) consider(first_child[round[q]] + k);
    }
    for (const TreeScratch& s : scratch) T.boxes += s.boxes;
    if (cells.size() == 1) {  // the root was not split: no tree
        T.init_full(p);
        return;
    }
    // Nodes, leaves and tapes, in cell order (deterministic; parents precede children).
    T.nodes.resize(cells.size());
    T.boxes_.resize(cells.size());
    std::vector<TapeTree::Leaf> kept_at(cells.size());
    T.tapes.reserve(cells.size() + 1);  // (moves only: the leaves' code pointers stay valid)
    for (size_t i = 0; i < cells.size(); ++i) {
        TreeCell& c = cells[i];
        TapeTree::Node& node = T.nodes[i];
        for (int a = 0; a < 3; ++a) T.boxes_[i].lo[a] = c.lo[a], T.boxes_[i].hi[a] = c.hi[a];
        if (first_child[i] != kNone) {
            const glm::vec3 mid = 0.5f * (c.lo + c.hi);
            for (int a = 0; a < 3; ++a) node.c[a] = mid[a];
            node.child = first_child[i];
            for (uint32_t k = 0; k < 8; ++k) T.boxes_[first_child[i] + k].parent = static_cast<uint32_t>(i);
            if (keep[i]) {
                kept_at[i].len = static_cast<uint32_t>(c.tape.code.size());
                kept_at[i].out = c.tape.out;
                T.tapes.push_back(std::move(c.tape.code));
                kept_at[i].code = T.tapes.back().data();
                T.max_regs = std::max(T.max_regs, c.tape.num_regs);
            }
            continue;
        }
        TapeTree::Leaf L{};
        for (int a = 0; a < 3; ++a) L.lo[a] = c.lo[a], L.hi[a] = c.hi[a];
        L.ivlo = c.ivlo, L.ivhi = c.ivhi;
        L.node = static_cast<uint32_t>(i);
        if (c.ref_cell != kNone) {
            const TapeTree::Leaf& k = kept_at[c.ref_cell];
            L.code = k.code, L.len = k.len, L.out = k.out;
        } else {
            L.len = static_cast<uint32_t>(c.tape.code.size());
            L.out = c.tape.out;
            T.tapes.push_back(std::move(c.tape.code));
            L.code = T.tapes.back().data();
            T.max_regs = std::max(T.max_regs, c.tape.num_regs);
        }
        node.child = TapeTree::kLeafBit | static_cast<uint32_t>(T.leaves.size());
        T.leaves.push_back(L);
    }
}

// The instructions of `p` that outputs [first, end) need (dead code removed, registers
// unchanged, so the outputs stay where they were).
std::vector<Instr> live_code(const Program& p, size_t first) {
    std::vector<uint8_t> need(std::max<size_t>(p.num_regs, 1), 0);
    for (size_t o = first; o < p.outputs.size(); ++o) need[p.outputs[o]] = 1;
    std::vector<Instr> rev;
    for (size_t i = p.code.size(); i-- > 0;) {
        const Instr& in = p.code[i];
        if (!need[in.out]) continue;
        need[in.out] = 0;
        const int ar = kOpInfo[static_cast<int>(in.op)].arity;
        if (ar > 0) need[in.a] = 1;
        if (ar > 1) need[in.b] = 1;
        if (ar > 2) need[in.c] = 1;
        rev.push_back(in);
    }
    return {rev.rbegin(), rev.rend()};
}

// Everything the workers share, resolved once per render.
struct Frame {
    const CompiledScene* scene = nullptr;
    Camera camera;
    int width = 0, height = 0, samples = 1, tile = 16, max_steps = 256, max_bounces = 3;
    float eps = 1e-4f, max_dist = 100.0f, time = 0.0f;
    bool cone = false, shadows = true, ao = true, has_distance = true, has_material = true;
    bool clip = false;
    // Raw fields (.vm models) make no Lipschitz claim: see march_raw().
    bool raw = false;
    float raw_lipschitz = 1.0f, raw_max_step = 0.05f;
    glm::vec3 lo{0}, hi{0};
    std::vector<glm::vec4> planes;  // floor planes as half-spaces n.p <= w (with a margin)
    glm::vec3 solid_lo{0}, solid_hi{0};  // ... and the box of everything else
    std::vector<glm::vec2> offsets;
    bool want_depth = false, want_normal = false, want_steps = false;
    RenderView view = RenderView::Shaded;
    glm::vec3 ambient{0}, background{0};
    float relax = kRelax;           // over-relaxation factor (1 = plain Hart)
    bool premarch = true;           // tile cone pre-marching (Worker::tile_start)
    TapeTree tree;                  // leaf 0 (the full distance program) at least
    Program regs;                   // no code: sizes the workers' distance register files
    std::vector<Instr> shade_code;  // the shading program without the distance output's code

    explicit Frame(const CompiledScene& s) : scene(&s), camera(s.camera, std::max(s.render.width, 1), std::max(s.render.height, 1)) {}

    float thr(float path) const { return eps * std::max(path, 1.0f); }
    float footprint(float path) const { return camera.footprint_base() + camera.footprint_slope() * path; }
    float bias(const glm::vec3& p, float path) const { return 4.0f * thr(path) + 2e-5f * (1.0f + maxabs3(p)); }

    // Clips [t_min, t_max] to where surfaces can be: the bounding box (clip), or, in a scene
    // with floor planes, the hull of the parts of the ray in the box of everything else
    // (solid_lo/hi, may be empty) or under a plane (planes). An empty interval becomes
    // t_min = +inf.
    void clip_ray(const glm::vec3& o, const glm::vec3& d, float& t_min, float& t_max) const {
        if (!planes.empty()) return clip_hull(o, d, t_min, t_max);
        if (!clip) return;
        clip_box(lo, hi, o, d, t_min, t_max);
    }
    static void clip_box(const glm::vec3& lo, const glm::vec3& hi, const glm::vec3& o, const glm::vec3& d, float& t_min,
                         float& t_max) {
        for (int a = 0; a < 3; ++a) {
            if (std::fabs(d[a]) < 1e-30f) {
                if (o[a] < lo[a] || o[a] > hi[a]) t_min = INFINITY;
                continue;
            }
            float inv = 1.0f / d[a];
            float t1 = (lo[a] - o[a]) * inv, t2 = (hi[a] - o[a]) * inv;
            if (t1 > t2) std::swap(t1, t2);
            t_min = std::max(t_min, t1);
            t_max = std::min(t_max, t2);
        }
        if (!(t_min <= t_max)) t_min = INFINITY;
    }
    void clip_hull(const glm::vec3& o, const glm::vec3& d, float& t_min, float& t_max) const {
        float a = INFINITY, b = -INFINITY;
        if (solid_lo.x <= solid_hi.x && solid_lo.y <= solid_hi.y && solid_lo.z <= solid_hi.z) {
            float t0 = t_min, t1 = t_max;
            clip_box(solid_lo, solid_hi, o, d, t0, t1);
            if (t0 <= t1) a = t0, b = t1;
        }
        for (const glm::vec4& q : planes) {
            // Under the plane where s + v t <= 0.
            const float s = q.x * o.x + q.y * o.y + q.z * o.z - q.w, v = q.x * d.x + q.y * d.y + q.z * d.z;
            float t0 = t_min, t1 = t_max;
            if (v < 0.0f) t0 = std::max(t0, -s / v);
            else if (v > 0.0f) t1 = std::min(t1, -s / v);
            else if (!(s <= 0.0f)) continue;
            if (t0 <= t1) a = std::min(a, t0), b = std::max(b, t1);
        }
        t_min = a, t_max = b;
        if (!(t_min <= t_max)) t_min = INFINITY;
    }
};

// The lane window: up to kWindow rays in flight, structure of arrays so that the per-step
// work (point gather, the distance update) vectorises. Finished lanes are refilled with the
// last lane (swap-remove) and then from the queue. With a tape tree, each lane caches the
// leaf holding its point (box and interval), and lanes are evaluated grouped by leaf.
struct Lanes {
    alignas(64) float ox[kWindow], oy[kWindow], oz[kWindow], dx[kWindow], dy[kWindow], dz[kWindow];
    alignas(64) float t[kWindow], tmax[kWindow], t0[kWindow], sg[kWindow], w[kWindow], a[kWindow], b[kWindow];
    alignas(64) float om[kWindow], pr[kWindow], sl[kWindow];  // over-relaxation: factor, previous radius, step
    alignas(64) float x[kWindow], y[kWindow], z[kWindow], dist[kWindow];
    alignas(64) float blo[3][kWindow], bhi[3][kWindow], ivlo[kWindow], ivhi[kWindow];  // the lane's leaf
    alignas(64) int32_t steps[kWindow], done[kWindow], idx[kWindow];
    alignas(64) uint32_t ray[kWindow], leaf[kWindow];
    void load(int i, const RaySet& rs, uint32_t r, float relax) {
        ox[i] = rs.ox[r], oy[i] = rs.oy[r], oz[i] = rs.oz[r];
        dx[i] = rs.dx[r], dy[i] = rs.dy[r], dz[i] = rs.dz[r];
        t[i] = rs.tmin[r], tmax[i] = rs.tmax[r], t0[i] = rs.t0[r];
        sg[i] = rs.inside[r] ? -1.0f : 1.0f;
        w[i] = 0.0f, a[i] = 0.0f, b[i] = 0.0f;
        om[i] = relax, pr[i] = 0.0f, sl[i] = 0.0f;
        steps[i] = 0, done[i] = 0;
        ray[i] = r;
        for (int k = 0; k < 3; ++k) blo[k][i] = INFINITY, bhi[k][i] = -INFINITY;  // no leaf yet
        leaf[i] = 0, ivlo[i] = -INFINITY, ivhi[i] = INFINITY;
    }
    void set_leaf(int i, uint32_t id, const TapeTree::Leaf& L) {
        leaf[i] = id;
        for (int k = 0; k < 3; ++k) blo[k][i] = L.lo[k], bhi[k][i] = L.hi[k];
        ivlo[i] = L.ivlo, ivhi[i] = L.ivhi;
    }
    void move(int from, int to) {
        ox[to] = ox[from], oy[to] = oy[from], oz[to] = oz[from];
        dx[to] = dx[from], dy[to] = dy[from], dz[to] = dz[from];
        t[to] = t[from], tmax[to] = tmax[from], t0[to] = t0[from], sg[to] = sg[from];
        w[to] = w[from], a[to] = a[from], b[to] = b[from];
        om[to] = om[from], pr[to] = pr[from], sl[to] = sl[from];
        x[to] = x[from], y[to] = y[from], z[to] = z[from], dist[to] = dist[from];
        for (int k = 0; k < 3; ++k) blo[k][to] = blo[k][from], bhi[k][to] = bhi[k][from];
        ivlo[to] = ivlo[from], ivhi[to] = ivhi[from], leaf[to] = leaf[from];
        steps[to] = steps[from], done[to] = done[from], ray[to] = ray[from];
    }
    // Where ray i leaves its leaf's box (its t; possibly a little below t[i] by rounding).
    float exit_t(int i) const {
        float te = INFINITY;
        const float o[3] = {ox[i], oy[i], oz[i]}, d[3] = {dx[i], dy[i], dz[i]};
        for (int k = 0; k < 3; ++k) {
            if (d[k] > 0.0f) te = std::min(te, (bhi[k][i] - o[k]) / d[k]);
            else if (d[k] < 0.0f) te = std::min(te, (blo[k][i] - o[k]) / d[k]);
        }
        return te;
    }
};

// Groups up to kWindow lanes by leaf: order[start[b] .. start[b + 1]) are the lanes of
// bucket b, whose leaf is key_of[b]. Open addressing with generation stamps (no clearing).
struct Buckets {
    static constexpr int kSlots = 1024;
    static_assert(kSlots >= 2 * kWindow);
    uint32_t key[kSlots], gen[kSlots] = {};
    uint16_t id[kSlots];
    uint32_t cur = 0;
    uint32_t key_of[kWindow];
    int count[kWindow + 1], start[kWindow + 1], nb = 0;
    uint16_t bucket[kWindow], order[kWindow];
    void build(const uint32_t* leaf, int n) {
        if (++cur == 0) std::fill_n(gen, kSlots, 0u), cur = 1;
        nb = 0;
        for (int i = 0; i < n; ++i) {
            const uint32_t k = leaf[i];
            uint32_t h = (k * 2654435761u) >> 22;  // 10 bits
            while (gen[h] == cur && key[h] != k) h = (h + 1) & (kSlots - 1);
            if (gen[h] != cur) {
                gen[h] = cur, key[h] = k, id[h] = static_cast<uint16_t>(nb);
                key_of[nb] = k, count[nb] = 0;
                ++nb;
            }
            bucket[i] = id[h];
            ++count[id[h]];
        }
        int acc = 0;
        for (int b = 0; b < nb; ++b) start[b] = acc, acc += count[b];
        start[nb] = acc;
        for (int b = 0; b < nb; ++b) count[b] = start[b];
        for (int i = 0; i < n; ++i) order[count[bucket[i]]++] = static_cast<uint16_t>(i);
    }
};

class Worker {
public:
    explicit Worker(const Frame& f) : f_(f), T_(f.tree), dist_(f.regs) {
        if (f.has_material) shade_ = std::make_unique<Evaluator>(f.scene->shading);
        lanes_ = std::make_unique<Lanes>();
        buckets_ = std::make_unique<Buckets>();
    }

    void render_tile(int x0, int y0, int x1, int y1, Image& img, AovPlane* depth, AovPlane* normal, AovPlane* steps);
    void render_tile_2d(int x0, int y0, int x1, int y1, Image& img, AovPlane* depth);

    RenderStats stats;

private:
    const Frame& f_;
    const TapeTree& T_;
    Evaluator dist_;  // runs tapes of T_ (eval_code) on a register file big enough for all
    std::unique_ptr<Evaluator> shade_;

    // Scratch, reused tile after tile (no allocation once warm).
    RaySet rays_, next_, hits_, shadow_;
    std::vector<float> t_, accum_, px_, py_, pz_, pd_, nx_, ny_, nz_, mat_, vis_, sw_;
    std::vector<uint8_t> hit_;
    std::vector<int> steps_;
    std::vector<float> prim_depth_, prim_steps_, prim_n_, prim_aw_;
    std::vector<float> ev_t_, ev_w_, trans_;
    std::vector<int> ev_n_;
    std::vector<uint32_t> local_, sh_idx_;
    std::vector<float> lw_, lnx_, lny_, lnz_, ao_, lrad_;
    uint32_t pleaf_[kWindow];
    int kind_ = RenderStats::kRays;  // what the distance evaluations are for (stats)
    alignas(64) float gx_[kBatch], gy_[kBatch], gz_[kBatch];

    std::unique_ptr<Lanes> lanes_;
    std::unique_ptr<Buckets> buckets_;

    // Distances at n <= kWindow points that all lie in leaf `id`.
    void eval_leaf(uint32_t id, const float* x, const float* y, const float* z, int n, float* out) {
        const TapeTree::Leaf& lf = T_.leaves[id];
        const Instr* code = lf.code;
        for (int i0 = 0; i0 < n; i0 += kBatch) {
            const int m = std::min(kBatch, n - i0);
            dist_.eval_code(code, lf.len, x + i0, y + i0, z + i0, m, f_.time);
            std::copy_n(dist_.reg_data(lf.out), m, out + i0);
        }
        stats.distance_points += static_cast<uint64_t>(n);
        stats.distance_points_by[kind_] += static_cast<uint64_t>(n);
        g_dbg.pts[id == 0][kind_] += n; g_dbg.ins[id == 0][kind_] += uint64_t(n) * lf.len;
        stats.distance_instructions += static_cast<uint64_t>(n) * lf.len;
    }

    // Distances at n <= kWindow points whose leaves are leaf[0, n): one batch per leaf.
    void eval_grouped(const float* x, const float* y, const float* z, const uint32_t* leaf, int n, float* out) {
        bool same = true;
        for (int i = 1; i < n; ++i) same &= leaf[i] == leaf[0];
        if (same) return eval_leaf(leaf[0], x, y, z, n, out);
        Buckets& B = *buckets_;
        B.build(leaf, n);
        for (int b = 0; b < B.nb; ++b) {
            const TapeTree::Leaf& lf = T_.leaves[B.key_of[b]];
            const Instr* code = lf.code;
            for (int j0 = B.start[b]; j0 < B.start[b + 1]; j0 += kBatch) {
                const int m = std::min(kBatch, B.start[b + 1] - j0);
                const uint16_t* ord = B.order + j0;
                for (int j = 0; j < m; ++j) gx_[j] = x[ord[j]], gy_[j] = y[ord[j]], gz_[j] = z[ord[j]];
                dist_.eval_code(code, lf.len, gx_, gy_, gz_, m, f_.time);
                const float* d = dist_.reg_data(lf.out);
                for (int j = 0; j < m; ++j) out[ord[j]] = d[j];
            }
            const uint64_t cnt = static_cast<uint64_t>(B.start[b + 1] - B.start[b]);
            stats.distance_points += cnt;
            stats.distance_points_by[kind_] += cnt;
            g_dbg.pts[B.key_of[b] == 0][kind_] += cnt; g_dbg.ins[B.key_of[b] == 0][kind_] += cnt * lf.len;
            stats.distance_instructions += cnt * lf.len;
        }
    }

    // Lanes [0, n) whose point left their cached leaf box find their leaf.
    // Then returns in L.idx[0, return) the lanes that may jump (empty leaf for their sign).
    int locate_lanes(Lanes& L, int n) {
        alignas(64) int32_t out[kWindow];
        for (int i = 0; i < n; ++i) {
            const bool in = (L.x[i] >= L.blo[0][i]) & (L.x[i] <= L.bhi[0][i]) & (L.y[i] >= L.blo[1][i]) &
                            (L.y[i] <= L.bhi[1][i]) & (L.z[i] >= L.blo[2][i]) & (L.z[i] <= L.bhi[2][i]);
            out[i] = in ? 0 : 1;
        }
        int m = 0;
        for (int i = 0; i < n; ++i) {
            L.idx[m] = i;
            m += out[i];
        }
        for (int j = 0; j < m; ++j) {
            const int i = L.idx[j];
            const uint32_t id = T_.locate_from(L.leaf[i], L.x[i], L.y[i], L.z[i]);
            L.set_leaf(i, id, T_.leaves[id]);
        }
        for (int i = 0; i < n; ++i) out[i] = (L.sg[i] > 0.0f ? L.ivlo[i] : -L.ivhi[i]) > 0.0f;
        m = 0;
        for (int i = 0; i < n; ++i) {
            L.idx[m] = i;
            m += out[i];
        }
        return m;
    }

    // Collects the finished lanes without branching, then swap-removes them from the highest
    // index down (so the lane moved in is always a live one).
    template <class Finish>
    void retire(Lanes& L, int& n, Finish&& finish) {
        int nd = 0;
        for (int i = 0; i < n; ++i) {
            L.idx[nd] = i;
            nd += L.done[i] != 0;
        }
        while (nd > 0) {
            const int i = L.idx[--nd];
            finish(L, i);
            if (i != --n) L.move(n, i);
        }
    }

    // Runs the rays of `rs` through the lane window. `init(L, i)` sets up lane i after its
    // ray is loaded; `update(L, n, d)` consumes the distances of lanes [0, n) (a vectorisable
    // loop that advances t and sets L.done); `finish(L, i)` records a finished lane. Rays
    // with an empty [tmin, tmax] go to `empty(r)` without an evaluation.
    // With a tape tree, a lane whose leaf is empty for it (signed lower bound slo > 0) may
    // jump: `skip(L, i, slo, t_exit)` decides (and sets L.t[i] and any state) or returns
    // false; a ray that jumps past tmax ends through `out(L, i)` (which sets a miss) and
    // `finish`. t_exit is where the ray leaves the leaf's box, or tmax if that comes first
    // (nothing beyond tmax is ever sampled).
    template <class Init, class Update, class Finish, class Empty, class Skip, class Out>
    void run(const RaySet& rs, Init&& init, Update&& update, Finish&& finish, Empty&& empty, Skip&& skip, Out&& out) {
        Lanes& L = *lanes_;
        int n = 0;
        size_t next = 0;
        const size_t count = rs.size();
        const bool tree = T_.active;
        for (;;) {
            while (n < kWindow && next < count) {
                const uint32_t r = static_cast<uint32_t>(next++);
                if (!(rs.tmin[r] <= rs.tmax[r])) {
                    empty(r);
                    continue;
                }
                L.load(n, rs, r, f_.relax);
                init(L, n);
                ++n;
            }
            if (n == 0) return;
            for (int i = 0; i < n; ++i) {
                L.x[i] = L.ox[i] + L.t[i] * L.dx[i];
                L.y[i] = L.oy[i] + L.t[i] * L.dy[i];
                L.z[i] = L.oz[i] + L.t[i] * L.dz[i];
            }
            if (tree) {
                const int nc = locate_lanes(L, n);
                bool any_out = false;
                for (int j = 0; j < nc; ++j) {
                    const int i = L.idx[j];
                    float slo = L.sg[i] > 0.0f ? L.ivlo[i] : -L.ivhi[i];
                    for (int it = 0; slo > 0.0f && it < 64; ++it) {
                        if (!skip(L, i, slo, std::min(L.exit_t(i), L.tmax[i]))) break;
                        ++stats.skips;
                        if (!(L.t[i] <= L.tmax[i])) {
                            out(L, i);
                            L.done[i] = 1;
                            any_out = true;
                            break;
                        }
                        L.x[i] = L.ox[i] + L.t[i] * L.dx[i];
                        L.y[i] = L.oy[i] + L.t[i] * L.dy[i];
                        L.z[i] = L.oz[i] + L.t[i] * L.dz[i];
                        const uint32_t id = T_.locate_from(L.leaf[i], L.x[i], L.y[i], L.z[i]);
                        L.set_leaf(i, id, T_.leaves[id]);
                        slo = L.sg[i] > 0.0f ? L.ivlo[i] : -L.ivhi[i];
                    }
                }
                if (any_out) {
                    retire(L, n, finish);
                    if (n == 0) continue;
                }
                eval_grouped(L.x, L.y, L.z, L.leaf, n, L.dist);
            } else {
                eval_leaf(0, L.x, L.y, L.z, n, L.dist);
            }
            update(L, n, static_cast<const float*>(L.dist));
            retire(L, n, finish);
        }
    }

    // Distance at `count` arbitrary points (each batch grouped by leaf).
    void eval_points(const float* x, const float* y, const float* z, size_t count, float* out) {
        if (!T_.active) {
            for (size_t i = 0; i < count; i += kWindow)
                eval_leaf(0, x + i, y + i, z + i, static_cast<int>(std::min<size_t>(kWindow, count - i)), out + i);
            return;
        }
        uint32_t prev = 0;
        for (size_t i0 = 0; i0 < count; i0 += kWindow) {
            const int m = static_cast<int>(std::min<size_t>(kWindow, count - i0));
            for (int j = 0; j < m; ++j) {
                const float px = x[i0 + j], py = y[i0 + j], pz = z[i0 + j];
                const TapeTree::Leaf& lf = T_.leaves[prev];
                const bool in = px >= lf.lo[0] && px <= lf.hi[0] && py >= lf.lo[1] && py <= lf.hi[1] && pz >= lf.lo[2] &&
                                pz <= lf.hi[2];
                if (!in) prev = T_.locate_from(prev, px, py, pz);
                pleaf_[j] = prev;
            }
            eval_grouped(x + i0, y + i0, z + i0, pleaf_, m, out + i0);
        }
    }

    // The jump of an (over-relaxed) sphere-traced lane in an empty leaf: only if no point of
    // the leaf could stop the ray (slo >= its hit threshold up to the landing point). Lands
    // slo beyond the box's exit: the exit point is in the box, so its distance is >= slo.
    // If the check of the last over-relaxed step is not sure to pass (r >= slo is all we
    // know), it is treated as failed instead, without an evaluation: back to the previous
    // sphere's boundary, omega = 1 (as march() does), and the jump is decided from there.
    bool skip_sphere(Lanes& L, int i, float slo, float te) {
        if (L.om[i] > 1.0f && slo + L.pr[i] < L.sl[i]) {
            L.t[i] += L.pr[i] - L.sl[i];
            L.om[i] = 1.0f, L.pr[i] = 0.0f, L.sl[i] = 0.0f;
            return true;
        }
        const float tn = std::max(te, L.t[i]) + slo;
        if (!(slo >= f_.thr(L.t0[i] + tn))) return false;
        L.t[i] = tn;
        L.pr[i] = 0.0f, L.sl[i] = 0.0f;
        return true;
    }

    float tile_start(int x0, int y0, int x1, int y1);

    void push_primary(RaySet& rs, const Ray& r, float weight, uint32_t prim, float start) {
        float tmin = start, tmax = f_.max_dist;
        f_.clip_ray(r.origin, r.dir, tmin, tmax);
        rs.push(r.origin, r.dir, tmin, tmax, 0.0f, glm::vec3(weight), prim, false);
    }
    void push_secondary(RaySet& rs, const glm::vec3& o, const glm::vec3& d, float path, const glm::vec3& w, uint32_t prim,
                        bool in) {
        float tmin = 0.0f, tmax = f_.max_dist;
        f_.clip_ray(o, d, tmin, tmax);
        rs.push(o, d, tmin, tmax, path, w, prim, in);
    }

    void march(const RaySet& rs);
    void march_raw(const RaySet& rs, bool shadow);
    void cone_march(const RaySet& rs);
    void compute_normals(const RaySet& h);
    void compute_materials(const RaySet& h);
    void shadow_hard(const RaySet& rs);
    void shadow_soft(const RaySet& rs);
    void shade(const RaySet& h, int gen, RaySet& next);
    void add(uint32_t prim, const glm::vec3& c) {
        const size_t p = prim / static_cast<uint32_t>(f_.samples);
        accum_[p * 3 + 0] += c.x;
        accum_[p * 3 + 1] += c.y;
        accum_[p * 3 + 2] += c.z;
    }
};

// Sphere tracing (outside rays on d, inside rays on -d). Results in t_, hit_, steps_.
void Worker::march(const RaySet& rs) {
    if (f_.raw) return march_raw(rs, false);
    const size_t n = rs.size();
    t_.resize(n);
    hit_.assign(n, 0);
    steps_.assign(n, 0);
    const int max_steps = f_.max_steps;
    const float eps = f_.eps;
    run(
        rs, [](Lanes&, int) {},
        [&](Lanes& L, int m, const float* d) {
            for (int i = 0; i < m; ++i) {
                const float s = L.sg[i] * d[i], r = std::fabs(s);
                // Over-relaxation: step omega * d while consecutive unbounding spheres
                // overlap; when they do not, or the step went through the surface (s < 0),
                // a surface may lie between: step back inside the previous sphere and
                // continue with omega = 1. Near the surface (d within kRelaxNear hit
                // thresholds) the steps are plain, so that grazing rays are sampled where
                // plain sphere tracing samples them and hit or miss alike.
                const float thr = eps * std::max(L.t0[i] + L.t[i], 1.0f);
                const bool fail = (L.om[i] > 1.0f) & (L.sl[i] > L.pr[i]) & ((r + L.pr[i] < L.sl[i]) | (s < 0.0f));
                // (A relaxed step past tmax is not taken: only a plain step may end the ray.)
                const float om = (s > kRelaxNear * thr) & (L.t[i] + L.om[i] * s <= L.tmax[i]) ? L.om[i] : 1.0f;
                const float step = fail ? L.pr[i] - L.sl[i] : om * s;
                L.om[i] = fail ? 1.0f : L.om[i];
                L.sl[i] = step;
                L.pr[i] = r;
                const int st = ++L.steps[i];
                const bool stop = ((s < thr) & !fail) | (st >= max_steps);  // hit, or out of steps (decided in finish)
                const float tn = L.t[i] + step;
                const bool out = !(tn <= L.tmax[i]);  // also NaN
                L.a[i] = fail ? INFINITY : s;
                L.t[i] = stop ? L.t[i] : tn;
                L.done[i] = stop | out;
            }
        },
        [&](Lanes& L, int i) {
            const uint32_t r = L.ray[i];
            const float s = L.a[i], path = L.t0[i] + L.t[i];
            steps_[r] = L.steps[i];
            hit_[r] = s < f_.thr(path) || (L.steps[i] >= max_steps && s < f_.footprint(path));
            // A hit moves on by its last distance: still outside (1-Lipschitz), and much
            // closer to the surface, wherever the last step began (same with --baseline).
            t_[r] = hit_[r] && s > 0.0f ? L.t[i] + s : L.t[i];
        },
        [&](uint32_t r) { t_[r] = rs.tmax[r]; },
        [&](Lanes& L, int i, float slo, float te) { return skip_sphere(L, i, slo, te); },
        [](Lanes& L, int i) { L.a[i] = INFINITY, L.t[i] = L.tmax[i]; });
}

// Marching a raw field (no distance bound): steps of |f| / L, with L a Lipschitz estimate
// sampled over the volume (render()), clamped to [one pixel footprint, raw_max_step]; a
// sign change (f <= 0) is refined by bisection to the outside end of the bracket. Thin features
// (under a pixel or where the estimate is low) can be missed: the price of no bound.
// Lane state: a = previous t, b / w = bisection bracket (lo, hi), sl = bisection iterations
// (0 while marching), om = 1 when the ray ended as a hit.
// `shadow`: results go to vis_ (0 = blocked) instead of t_ / hit_ / steps_.
void Worker::march_raw(const RaySet& rs, bool shadow) {
    const size_t n = rs.size();
    if (shadow) {
        vis_.assign(n, 1.0f);
    } else {
        t_.resize(n);
        hit_.assign(n, 0);
        steps_.assign(n, 0);
    }
    const int max_steps = f_.max_steps;
    constexpr int kBisect = 12;
    const float inv_l = 1.0f / f_.raw_lipschitz;
    run(
        rs, [](Lanes& L, int i) { L.a[i] = -1.0f, L.sl[i] = 0.0f, L.om[i] = 0.0f; },
        [&](Lanes& L, int m, const float* dist) {
            for (int i = 0; i < m; ++i) {
                const float s = L.sg[i] * dist[i], t = L.t[i], path = L.t0[i] + t;
                const int st = ++L.steps[i];
                bool done = false, hit = false;
                if (L.sl[i] > 0.0f) {
                    // Bisection: keep the outside end in b, the inside end in w.
                    if (s < 0.0f) L.w[i] = t;
                    else L.b[i] = t;
                    L.sl[i] += 1.0f;
                    if (L.sl[i] > kBisect || L.w[i] - L.b[i] < f_.thr(path)) {
                        L.t[i] = L.b[i];
                        done = hit = true;
                    } else {
                        L.t[i] = 0.5f * (L.b[i] + L.w[i]);
                    }
                } else if (s <= 0.0f) {  // a sign change (values are not distances: "close" means nothing)
                    if (s == 0.0f || L.a[i] < 0.0f || shadow) {
                        done = hit = true;
                    } else {
                        L.b[i] = L.a[i], L.w[i] = t, L.sl[i] = 1.0f;
                        L.t[i] = 0.5f * (L.b[i] + L.w[i]);
                    }
                } else {
                    const float step = s == s ? std::clamp(s * inv_l, f_.footprint(path), f_.raw_max_step) : f_.footprint(path);
                    L.a[i] = t;
                    L.t[i] = t + step;
                    done = !(L.t[i] <= L.tmax[i]);
                }
                if (!done && st >= max_steps) {
                    done = true;
                    hit = L.sl[i] > 0.0f;  // inside a bracket: take its outside end
                    if (hit) L.t[i] = L.b[i];
                }
                L.om[i] = hit ? 1.0f : 0.0f;
                L.done[i] = done;
            }
        },
        [&](Lanes& L, int i) {
            const uint32_t r = L.ray[i];
            if (shadow) {
                vis_[r] = L.om[i] > 0.0f ? 0.0f : 1.0f;
                return;
            }
            t_[r] = L.t[i];
            hit_[r] = L.om[i] > 0.0f;
            steps_[r] = L.steps[i];
        },
        [&](uint32_t r) {
            if (!shadow) t_[r] = rs.tmax[r];
        },
        [&](Lanes& L, int i, float, float te) {
            // No sign change in an empty leaf: past its exit (a quarter pixel beyond, for
            // progress); the current point is the outside end of a later bracket.
            if (L.sl[i] > 0.0f) return false;  // bisecting
            const float t = L.t[i], tn = std::max(te, t);
            L.a[i] = t;
            L.t[i] = tn + 0.25f * f_.footprint(L.t0[i] + tn) + 1e-6f * tn;
            return true;
        },
        [](Lanes& L, int i) { L.om[i] = 0.0f, L.t[i] = L.tmax[i]; });
}

// Cone tracing of primary rays: fills ev_* (partial hits), t_/hit_ (final hit), trans_
// (weight left for the final hit or the background) and steps_.
void Worker::cone_march(const RaySet& rs) {
    const size_t n = rs.size();
    t_.resize(n);
    hit_.assign(n, 0);
    steps_.assign(n, 0);
    ev_n_.assign(n, 0);
    ev_t_.resize(n * kConeEvents);
    ev_w_.resize(n * kConeEvents);
    trans_.assign(n, 1.0f);
    const int max_steps = f_.max_steps;
    auto emit = [&](uint32_t r, float t, float coverage) {
        int& k = ev_n_[r];
        if (k >= kConeEvents || !(coverage > 0.0f)) return;
        ev_t_[r * kConeEvents + k] = t;
        ev_w_[r * kConeEvents + k] = trans_[r] * coverage;
        trans_[r] *= 1.0f - coverage;
        ++k;
    };
    // Lane state: a = smallest d / r in the current edge zone (>= 1: none), b = its t,
    // w = 1 when the final state is a hit.
    run(
        rs, [](Lanes& L, int i) { L.a[i] = 2.0f; },
        [&](Lanes& L, int m, const float* dist) {
            for (int i = 0; i < m; ++i) {
                const uint32_t r = L.ray[i];
                const float d = dist[i], t = L.t[i], path = L.t0[i] + t;
                const float radius = std::max(f_.footprint(path), 1e-30f);
                const int st = ++L.steps[i];
                bool done = false, hit = false;
                if (d < f_.thr(path)) {
                    done = hit = true;  // the axis hits: this surface takes the remaining weight
                } else if (!(d == d)) {
                    done = true;
                } else {
                    const float rho = d / radius;
                    if (rho < 1.0f) {
                        if (rho < L.a[i]) L.a[i] = rho, L.b[i] = t;
                    } else if (L.a[i] < 1.0f) {
                        emit(r, L.b[i], 1.0f - L.a[i]);  // left an edge zone: composite its closest approach
                        L.a[i] = 2.0f;
                    }
                    if (trans_[r] < 1e-3f) {
                        done = true;  // fully covered by edges
                    } else if (st >= max_steps) {
                        done = true;
                        hit = d < radius;
                    } else {
                        L.t[i] = t + d;
                        done = !(L.t[i] <= L.tmax[i]);
                    }
                    if (done && !hit && L.a[i] < 1.0f) emit(r, L.b[i], 1.0f - L.a[i]);
                }
                L.w[i] = hit ? 1.0f : 0.0f;
                L.done[i] = done;
            }
        },
        [&](Lanes& L, int i) {
            const uint32_t r = L.ray[i];
            t_[r] = L.t[i];
            hit_[r] = L.w[i] > 0.0f;
            steps_[r] = L.steps[i];
        },
        [&](uint32_t r) { t_[r] = rs.tmax[r]; },
        [&](Lanes& L, int i, float slo, float te) {
            // Only where the cone cannot touch anything in the leaf (d >= its radius); leaving
            // an edge zone composites it, as the update would.
            const float tn = std::max(te, L.t[i]) + slo, path = L.t0[i] + tn;
            if (!(slo >= f_.thr(path) && slo >= f_.footprint(path))) return false;
            if (L.a[i] < 1.0f) {
                emit(L.ray[i], L.b[i], 1.0f - L.a[i]);
                L.a[i] = 2.0f;
            }
            L.t[i] = tn;
            return true;
        },
        [](Lanes& L, int i) { L.w[i] = 0.0f, L.t[i] = L.tmax[i]; });
}

void Worker::compute_normals(const RaySet& h) {
    static constexpr float kx[4] = {1, -1, -1, 1}, ky[4] = {-1, -1, 1, 1}, kz[4] = {-1, 1, -1, 1};
    const size_t n = h.size();
    px_.resize(n * 4), py_.resize(n * 4), pz_.resize(n * 4), pd_.resize(n * 4);
    for (size_t i = 0; i < n; ++i) {
        const glm::vec3 p = h.o(i);
        const float e = std::max(f_.thr(h.t0[i]), 2e-5f * (1.0f + maxabs3(p)));
        for (int k = 0; k < 4; ++k) {
            px_[i * 4 + k] = p.x + e * kx[k];
            py_[i * 4 + k] = p.y + e * ky[k];
            pz_[i * 4 + k] = p.z + e * kz[k];
        }
    }
    kind_ = RenderStats::kNormals;
    eval_points(px_.data(), py_.data(), pz_.data(), n * 4, pd_.data());
    kind_ = RenderStats::kRays;
    nx_.resize(n), ny_.resize(n), nz_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const float* d = &pd_[i * 4];
        glm::vec3 g(d[0] * kx[0] + d[1] * kx[1] + d[2] * kx[2] + d[3] * kx[3],
                    d[0] * ky[0] + d[1] * ky[1] + d[2] * ky[2] + d[3] * ky[3],
                    d[0] * kz[0] + d[1] * kz[1] + d[2] * kz[2] + d[3] * kz[3]);
        const float len2 = glm::dot(g, g);
        if (len2 > 1e-30f && std::isfinite(len2)) g *= 1.0f / std::sqrt(len2);
        else g = -h.d(i);  // flat or broken field: face the viewer
        nx_[i] = g.x, ny_[i] = g.y, nz_[i] = g.z;
    }
}

// Material channels at the hit points, sanitised (no NaN/inf, sensible ranges).
void Worker::compute_materials(const RaySet& h) {
    const size_t n = h.size();
    mat_.resize(n * kMatOut);
    for (size_t i0 = 0; i0 < n; i0 += kBatch) {
        const int m = static_cast<int>(std::min<size_t>(kBatch, n - i0));
        if (shade_) {
            const std::vector<Instr>& code = f_.shade_code;
            shade_->eval_code(code.data(), code.size(), h.ox.data() + i0, h.oy.data() + i0, h.oz.data() + i0, m, f_.time);
            stats.shading_points += static_cast<uint64_t>(m);
            stats.shading_instructions += static_cast<uint64_t>(m) * code.size();
            for (int c = 0; c < kMatOut; ++c) {
                const float* o = shade_->output(c + 1);
                for (int i = 0; i < m; ++i) mat_[(i0 + i) * kMatOut + c] = o[i];
            }
        } else {
            for (int i = 0; i < m; ++i) {
                float* q = &mat_[(i0 + i) * kMatOut];
                std::fill_n(q, kMatOut, 0.0f);
                q[kMatR] = q[kMatG] = q[kMatB] = 0.8f;
                q[kMatSpecular] = 0.5f, q[kMatShininess] = 32.0f, q[kMatIor] = 1.5f;
            }
        }
    }
    for (size_t i = 0; i < n; ++i) {
        float* q = &mat_[i * kMatOut];
        for (int c : {kMatR, kMatG, kMatB, kMatSpecular, kMatEmitR, kMatEmitG, kMatEmitB}) q[c] = nonneg(q[c]);
        q[kMatShininess] = std::isfinite(q[kMatShininess]) ? std::clamp(q[kMatShininess], 0.0f, 1e4f) : 32.0f;
        q[kMatReflect] = clamp01(q[kMatReflect]);
        q[kMatTransparency] = clamp01(q[kMatTransparency]);
        q[kMatIor] = (std::isfinite(q[kMatIor]) && q[kMatIor] > 1e-3f) ? q[kMatIor] : 1.5f;
    }
}

// Hard shadows: vis_[i] = 0 if the segment hits anything, else 1.
void Worker::shadow_hard(const RaySet& rs) {
    vis_.assign(rs.size(), 1.0f);
    const int max_steps = f_.max_steps;
    const float eps = f_.eps;
    run(
        rs, [](Lanes&, int) {},
        [&](Lanes& L, int m, const float* d) {
            for (int i = 0; i < m; ++i) {
                // Over-relaxed like march() (plain near surfaces); a blocker only counts at a
                // safe point (a point inside an occluder is one: it blocks).
                const float r = std::fabs(d[i]);
                const float thr = eps * std::max(L.t0[i] + L.t[i], 1.0f);
                const bool fail = (L.om[i] > 1.0f) & (L.sl[i] > L.pr[i]) & (r + L.pr[i] < L.sl[i]);
                const float om = (d[i] > kRelaxNear * thr) & (L.t[i] + L.om[i] * d[i] < L.tmax[i]) ? L.om[i] : 1.0f;
                const float step = fail ? L.pr[i] - L.sl[i] : om * d[i];
                L.om[i] = fail ? 1.0f : L.om[i];
                L.sl[i] = step;
                L.pr[i] = r;
                const int st = ++L.steps[i];
                const bool stop = ((d[i] < thr) & !fail) | (st >= max_steps);
                const float tn = L.t[i] + step;
                const bool out = !(tn < L.tmax[i]);  // also NaN: no occluder found
                L.a[i] = fail ? INFINITY : d[i];
                L.t[i] = stop ? L.t[i] : tn;
                L.done[i] = stop | out;
            }
        },
        [&](Lanes& L, int i) {
            const float d = L.a[i], path = L.t0[i] + L.t[i];
            const bool blocked = d < f_.thr(path) || (L.steps[i] >= max_steps && d < f_.footprint(path));
            vis_[L.ray[i]] = blocked ? 0.0f : 1.0f;
        },
        [](uint32_t) {}, [&](Lanes& L, int i, float slo, float te) { return skip_sphere(L, i, slo, te); },
        [](Lanes& L, int i) { L.a[i] = INFINITY, L.t[i] = L.tmax[i]; });
}

// Soft shadows; sw_[i] is the light's angular width (tangent) seen from ray i.
// Lane state: a = res (the smallest cone fraction), b = the previous positive distance.
// Over-relaxed like march() (om, pr, sl), but only far from any penumbra (estimate >= 2)
// and from surfaces, so the samples that decide res are where plain tracing takes them.
void Worker::shadow_soft(const RaySet& rs) {
    vis_.assign(rs.size(), 1.0f);
    const int max_steps = f_.max_steps;
    const float eps = f_.eps;
    run(
        rs,
        [&](Lanes& L, int i) {
            L.w[i] = sw_[L.ray[i]];
            L.a[i] = 1.0f;
            L.b[i] = 1e20f;
        },
        [&](Lanes& L, int m, const float* dist) {
            for (int i = 0; i < m; ++i) {
                const float h = dist[i], t = L.t[i], w = L.w[i], r = std::fabs(h);
                const float thr = eps * std::max(L.t0[i] + t, 1.0f);
                const bool pos = h > 0.0f;
                // The last over-relaxed step left the previous sphere (or entered a solid):
                // back to that sphere's boundary, plain steps from there; no sample taken.
                const bool fail = (L.om[i] > 1.0f) & (L.sl[i] > L.pr[i]) & ((r + L.pr[i] < L.sl[i]) | !pos);
                // Closest approach between this sample and the previous one (Quilez 2018;
                // for a step s longer than the previous distance b, the point both spheres
                // touch: y = (s^2 + h^2 - b^2) / 2s, which is h^2 / 2b when s = b);
                // inside an occluder, the (negative) depth relative to the cone.
                const float pb = L.b[i], ps = L.sl[i];
                const float y0 = ps > pb && pb < 1e19f ? (ps * ps + h * h - pb * pb) / (2.0f * ps) : h * h / (2.0f * pb);
                const float y = std::min(std::max(y0, 0.0f), 0.999f * h);
                const float dd = std::sqrt(std::max(h * h - y * y, 0.0f));
                const float est = pos ? dd / (w * std::max(t - y, 1e-20f)) : h / (w * std::max(t, 1e-20f));
                const float res = (est < L.a[i]) & !fail ? est : L.a[i];  // NaN keeps res
                L.a[i] = res;
                L.b[i] = fail ? L.b[i] : (pos ? h : 1e20f);
                // Sphere tracing outside; through an occluder in steps of a quarter cone width.
                const bool far = pos & (h > kSoftRelaxFar * w * t) & (h > kRelaxNear * thr) & (t + L.om[i] * h < L.tmax[i]);
                const float om = far ? L.om[i] : 1.0f;
                const float step = fail ? L.pr[i] - L.sl[i] : pos ? std::max(om * h, thr) : std::max(0.25f * w * t, thr);
                L.om[i] = fail ? 1.0f : L.om[i];
                L.sl[i] = step;
                L.pr[i] = r;
                const float tn = t + step;
                L.t[i] = tn;
                const int st = ++L.steps[i];
                L.done[i] = (h != h) | (res <= -1.0f) | (st >= max_steps) | !(tn < L.tmax[i]);
            }
        },
        [&](Lanes& L, int i) {
            const float res = std::clamp(L.a[i], -1.0f, 1.0f);
            vis_[L.ray[i]] = 0.25f * (1.0f + res) * (1.0f + res) * (2.0f - res);
        },
        [](uint32_t) {},
        [&](Lanes& L, int i, float slo, float te) {
            if (L.om[i] > 1.0f && slo + L.pr[i] < L.sl[i]) {  // as in skip_sphere()
                L.t[i] += L.pr[i] - L.sl[i];
                L.om[i] = 1.0f, L.pr[i] = 0.0f, L.sl[i] = 0.0f;
                return true;
            }
            // Only where every estimate in the leaf would be >= 2 (no penumbra there, with a
            // margin): d / (w t) >= slo / (w t_landing).
            const float tn = std::max(te, L.t[i]) + slo;
            if (!(slo >= 2.0f * L.w[i] * tn)) return false;
            L.t[i] = tn;
            L.b[i] = 1e20f;
            L.pr[i] = 0.0f, L.sl[i] = 0.0f;
            return true;
        },
        [](Lanes& L, int i) { L.t[i] = L.tmax[i]; });
}

// Shades a set of hit points of generation `gen`, adding to accum_ and spawning `next`.
void Worker::shade(const RaySet& h, int gen, RaySet& next) {
    const size_t n = h.size();
    if (n == 0) return;
    compute_normals(h);
    const bool need_shading = f_.view == RenderView::Shaded;
    if (gen == 0 && f_.want_normal) {
        for (size_t i = 0; i < n; ++i) {
            const uint32_t p = h.prim[i];
            if (h.wr[i] + h.wg[i] + h.wb[i] >= prim_aw_[p]) {
                prim_n_[p * 3 + 0] = nx_[i], prim_n_[p * 3 + 1] = ny_[i], prim_n_[p * 3 + 2] = nz_[i];
            }
        }
    }
    if (!need_shading) return;
    compute_materials(h);

    const bool can_spawn = gen < f_.max_bounces;
    const float min_w = kMinWeight / static_cast<float>(f_.samples);
    local_.clear(), lw_.clear(), lnx_.clear(), lny_.clear(), lnz_.clear();
    for (size_t i = 0; i < n; ++i) {
        const glm::vec3 P = h.o(i), D = h.d(i), W = h.w(i);
        const glm::vec3 N(nx_[i], ny_[i], nz_[i]);
        const glm::vec3 Nf = glm::dot(D, N) > 0.0f ? -N : N;  // facing the incoming ray
        const float* m = &mat_[i * kMatOut];
        const float ior = m[kMatIor];
        const float bias = f_.bias(P, h.t0[i]);
        if (h.inside[i]) {
            // Leaving a transparent solid: refract out, reflect back in (Fresnel / TIR).
            if (!can_spawn) continue;
            const glm::vec3 T = glm::refract(D, Nf, ior);
            float F = 1.0f;
            if (glm::dot(T, T) > 0.0f) F = schlick(-glm::dot(T, Nf), ior);
            const glm::vec3 wr = W * F, wt = W * (1.0f - F);
            if (max3(wr) >= min_w) push_secondary(next, P + Nf * bias, glm::reflect(D, Nf), h.t0[i], wr, h.prim[i], true);
            if (max3(wt) >= min_w) push_secondary(next, P - Nf * bias, glm::normalize(T), h.t0[i], wt, h.prim[i], false);
            continue;
        }
        add(h.prim[i], W * glm::vec3(m[kMatEmitR], m[kMatEmitG], m[kMatEmitB]));
        const float refl = can_spawn ? m[kMatReflect] : 0.0f;
        const float tr = can_spawn ? m[kMatTransparency] : 0.0f;
        const glm::vec3 lw = W * ((1.0f - refl) * (1.0f - tr));
        if (max3(lw) > 0.0f) {
            local_.push_back(static_cast<uint32_t>(i));
            lw_.insert(lw_.end(), {lw.x, lw.y, lw.z});
            lnx_.push_back(Nf.x), lny_.push_back(Nf.y), lnz_.push_back(Nf.z);
        }
        if (!can_spawn) continue;
        glm::vec3 w_refl = W * refl;
        if (tr > 0.0f) {
            const glm::vec3 base = W * ((1.0f - refl) * tr);
            const glm::vec3 T = glm::refract(D, Nf, 1.0f / ior);
            float F = 1.0f;
            if (glm::dot(T, T) > 0.0f) F = schlick(-glm::dot(D, Nf), ior);
            w_refl += base * F;
            const glm::vec3 wt = base * (1.0f - F) * glm::vec3(m[kMatR], m[kMatG], m[kMatB]);
            if (max3(wt) >= min_w) push_secondary(next, P - Nf * bias, glm::normalize(T), h.t0[i], wt, h.prim[i], true);
        }
        if (max3(w_refl) >= min_w) push_secondary(next, P + Nf * bias, glm::reflect(D, Nf), h.t0[i], w_refl, h.prim[i], false);
    }

    const size_t nl = local_.size();
    if (nl == 0) return;

    // Ambient (with occlusion).
    const glm::vec3 amb = f_.ambient;
    if (max3(amb) > 0.0f) {
        ao_.assign(nl, 1.0f);
        if (f_.ao && !f_.raw) {
            px_.resize(nl * kAoTaps), py_.resize(nl * kAoTaps), pz_.resize(nl * kAoTaps), pd_.resize(nl * kAoTaps);
            for (size_t k = 0; k < nl; ++k) {
                const glm::vec3 P = h.o(local_[k]);
                for (int j = 0; j < kAoTaps; ++j) {
                    const float s = 0.01f + 0.12f * static_cast<float>(j) / (kAoTaps - 1);
                    px_[k * kAoTaps + j] = P.x + lnx_[k] * s;
                    py_[k * kAoTaps + j] = P.y + lny_[k] * s;
                    pz_[k * kAoTaps + j] = P.z + lnz_[k] * s;
                }
            }
            kind_ = RenderStats::kAo;
            eval_points(px_.data(), py_.data(), pz_.data(), nl * kAoTaps, pd_.data());
            kind_ = RenderStats::kRays;
            for (size_t k = 0; k < nl; ++k) {
                float occ = 0.0f, sca = 1.0f;
                for (int j = 0; j < kAoTaps; ++j) {
                    const float s = 0.01f + 0.12f * static_cast<float>(j) / (kAoTaps - 1);
                    const float d = pd_[k * kAoTaps + j];
                    if (d < s) occ += (s - d) * sca;  // (NaN adds nothing)
                    sca *= 0.95f;
                }
                ao_[k] = clamp01(1.0f - 3.0f * occ);
            }
        }
        for (size_t k = 0; k < nl; ++k) {
            const float* m = &mat_[local_[k] * kMatOut];
            const glm::vec3 lw(lw_[k * 3], lw_[k * 3 + 1], lw_[k * 3 + 2]);
            add(h.prim[local_[k]], lw * glm::vec3(m[kMatR], m[kMatG], m[kMatB]) * amb * ao_[k]);
        }
    }

    // Direct light, one batched shadow pass per light.
    for (const ResolvedLight& light : f_.scene->lights) {
        const glm::vec3 radiance = light.color * light.intensity;
        if (!(max3(radiance) > 0.0f) || !std::isfinite(max3(radiance))) continue;
        glm::vec3 ldir = -light.direction;
        if (light.directional) {
            if (!(glm::dot(ldir, ldir) > 0.0f)) continue;
            ldir = glm::normalize(ldir);
        }
        shadow_.clear(), sh_idx_.clear(), sw_.clear(), lrad_.clear();
        for (size_t k = 0; k < nl; ++k) {
            const uint32_t i = local_[k];
            const glm::vec3 P = h.o(i), N(lnx_[k], lny_[k], lnz_[k]);
            glm::vec3 L = ldir;
            float dist = f_.max_dist, falloff = 1.0f;
            if (!light.directional) {
                L = light.position - P;
                dist = glm::length(L);
                if (!(dist > 1e-6f)) continue;
                L /= dist;
                falloff = 1.0f / (dist * dist);
            }
            const float ndl = glm::dot(N, L);
            if (!(ndl > 0.0f)) continue;
            const glm::vec3 V = -h.d(i);
            const glm::vec3 Hv = glm::normalize(L + V);
            const float* m = &mat_[i * kMatOut];
            const float ndh = std::max(glm::dot(N, Hv), 0.0f);
            const float spec = m[kMatSpecular] > 0.0f ? m[kMatSpecular] * std::pow(ndh, m[kMatShininess]) : 0.0f;
            const glm::vec3 lw(lw_[k * 3], lw_[k * 3 + 1], lw_[k * 3 + 2]);
            const glm::vec3 c = lw * radiance * falloff * (glm::vec3(m[kMatR], m[kMatG], m[kMatB]) * ndl + spec);
            if (!f_.shadows) {
                add(h.prim[i], c);
                continue;
            }
            const float bias = f_.bias(P, h.t0[i]);
            // Off the surface along the normal, and the march begins one more bias along the
            // light: at edges (where the normal blends two faces) a start closer than that
            // is in the other face's hit band, which would shadow the edge by chance.
            const glm::vec3 o = P + N * bias;
            float tmin = bias, tmax = light.directional ? f_.max_dist : std::max(dist - bias, 0.0f);
            f_.clip_ray(o, L, tmin, tmax);
            if (!(tmin <= tmax)) {
                add(h.prim[i], c);  // the segment never enters the scene's bounds
                continue;
            }
            shadow_.push(o, L, tmin, tmax, h.t0[i], glm::vec3(0), h.prim[i], false);
            sh_idx_.push_back(i);
            lrad_.insert(lrad_.end(), {c.x, c.y, c.z});
            sw_.push_back(light.directional ? light.radius : light.radius / dist);
        }
        if (shadow_.size() == 0) continue;
        kind_ = RenderStats::kShadows;
        if (f_.raw) march_raw(shadow_, true);
        else if (light.radius > 0.0f) shadow_soft(shadow_);
        else shadow_hard(shadow_);
        kind_ = RenderStats::kRays;
        for (size_t s = 0; s < shadow_.size(); ++s)
            if (vis_[s] > 0.0f) add(shadow_.prim[s], glm::vec3(lrad_[s * 3], lrad_[s * 3 + 1], lrad_[s * 3 + 2]) * vis_[s]);
    }
}

// Tile cone pre-marching: one march along the tile's central ray for all its primary rays.
// Every ray of the tile (directions within the corners' cone, origins within the corners')
// stays within R(t) = r0 + t * r1 of the axis point at the same t, so when the axis has
// distance d at t, the ball of radius d around it holds every ray's points up to t + step
// for step = d - R(t) - thr(t + d): no surface there, nor any point where plain tracing
// would stop (d >= its hit threshold). The rays then start at the final t.
float Worker::tile_start(int x0, int y0, int x1, int y1) {
    const Ray c = f_.camera.ray(0.5f * static_cast<float>(x0 + x1), 0.5f * static_cast<float>(y0 + y1));
    float r0 = 0.0f, r1 = 0.0f;
    for (int k = 0; k < 4; ++k) {
        const Ray q = f_.camera.ray(static_cast<float>(k & 1 ? x1 : x0), static_cast<float>(k & 2 ? y1 : y0));
        r0 = std::max(r0, glm::length(q.origin - c.origin));
        r1 = std::max(r1, glm::length(q.dir - c.dir));
    }
    r0 = r0 * 1.01f + 1e-6f, r1 = r1 * 1.01f + 1e-6f;  // rounding margin
    float t = 0.0f, tmax = f_.max_dist;
    f_.clip_ray(c.origin, c.dir, t, tmax);  // (not the start: other rays may enter the box sooner)
    t = 0.0f;
    constexpr int kMaxConeSteps = 32;
    for (int i = 0; i < kMaxConeSteps && t < f_.max_dist; ++i) {
        const glm::vec3 p = c.origin + c.dir * t;
        float d;
        eval_points(&p.x, &p.y, &p.z, 1, &d);
        const float step = d - (r0 + r1 * t) - f_.thr(t + d);
        if (!(step > 1e-3f * std::max(t, 1.0f))) break;  // also NaN
        t += step;
    }
    return t;
}

void Worker::render_tile(int x0, int y0, int x1, int y1, Image& img, AovPlane* depth, AovPlane* normal, AovPlane* steps) {
    const int tw = x1 - x0, th = y1 - y0;
    const int S = f_.samples;
    const size_t npix = static_cast<size_t>(tw) * th, nprim = npix * S;
    accum_.assign(npix * 3, 0.0f);
    prim_depth_.assign(nprim, f_.max_dist);
    prim_steps_.assign(nprim, 0.0f);
    prim_n_.assign(f_.want_normal ? nprim * 3 : 0, 0.0f);
    prim_aw_.assign(nprim, -1.0f);
    const float w0 = 1.0f / static_cast<float>(S);
    const glm::vec3 bg = f_.background;

    rays_.clear();
    const float start = f_.premarch ? tile_start(x0, y0, x1, y1) : 0.0f;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const uint32_t pix = static_cast<uint32_t>((y - y0) * tw + (x - x0));
            for (int s = 0; s < S; ++s) {
                const glm::vec2 o = f_.offsets[s];
                push_primary(rays_, f_.camera.ray(static_cast<float>(x) + o.x, static_cast<float>(y) + o.y), w0, pix * S + s, start);
            }
        }
    stats.primary_rays += nprim;

    // Generation 0.
    hits_.clear();
    if (f_.has_distance) {
        if (f_.cone) cone_march(rays_);
        else march(rays_);
    } else {
        t_.assign(nprim, f_.max_dist), hit_.assign(nprim, 0), steps_.assign(nprim, 0), trans_.assign(nprim, 1.0f), ev_n_.assign(nprim, 0);
    }
    for (size_t r = 0; r < nprim; ++r) {
        prim_steps_[r] = static_cast<float>(steps_[r]);
        const glm::vec3 O = rays_.o(r), D = rays_.d(r);
        float rest = w0;
        if (f_.cone) {
            for (int e = 0; e < ev_n_[r]; ++e) {
                const float t = ev_t_[r * kConeEvents + e], w = ev_w_[r * kConeEvents + e] * w0;
                hits_.push(O + D * t, D, 0, 0, t, glm::vec3(w), static_cast<uint32_t>(r), false);
                if (w > prim_aw_[r]) prim_aw_[r] = w, prim_depth_[r] = t;
            }
            rest = trans_[r] * w0;
        }
        if (hit_[r]) {
            hits_.push(O + D * t_[r], D, 0, 0, t_[r], glm::vec3(rest), static_cast<uint32_t>(r), false);
            if (rest > prim_aw_[r]) prim_aw_[r] = rest, prim_depth_[r] = t_[r];
        } else {
            add(static_cast<uint32_t>(r), bg * rest);
        }
    }
    if (f_.view == RenderView::Shaded || f_.want_normal) shade(hits_, 0, next_);

    // Secondary generations (reflection / refraction), iteratively.
    for (int gen = 1; gen <= f_.max_bounces && next_.size() > 0; ++gen) {
        std::swap(rays_, next_);
        next_.clear();
        march(rays_);
        hits_.clear();
        for (size_t r = 0; r < rays_.size(); ++r) {
            if (hit_[r]) {
                hits_.push(rays_.o(r) + rays_.d(r) * t_[r], rays_.d(r), 0, 0, rays_.t0[r] + t_[r], rays_.w(r), rays_.prim[r],
                           rays_.inside[r] != 0);
            } else if (!rays_.inside[r]) {
                add(rays_.prim[r], bg * rays_.w(r));
            }
        }
        shade(hits_, gen, next_);
    }
    next_.clear();

    // Resolve the tile.
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const size_t p = static_cast<size_t>((y - y0) * tw + (x - x0));
            const size_t o = static_cast<size_t>(y) * img.width + x;
            float st = 0.0f, dmin = f_.max_dist;
            glm::vec3 nsum(0.0f);
            for (int s = 0; s < S; ++s) {
                st += prim_steps_[p * S + s];
                dmin = std::min(dmin, prim_depth_[p * S + s]);
                if (f_.want_normal) nsum += glm::vec3(prim_n_[(p * S + s) * 3], prim_n_[(p * S + s) * 3 + 1], prim_n_[(p * S + s) * 3 + 2]);
            }
            st *= w0;
            if (f_.view == RenderView::Steps) {
                float rgb[3];
                heat_color(st / static_cast<float>(std::max(f_.max_steps, 1)), rgb);
                for (int c = 0; c < 3; ++c) img.pixels[o * 3 + c] = srgb_to_linear(rgb[c]);
            } else {
                for (int c = 0; c < 3; ++c) {
                    const float v = accum_[p * 3 + c];
                    img.pixels[o * 3 + c] = v >= 0.0f ? std::min(v, 1e30f) : 0.0f;  // never NaN or inf
                }
            }
            if (depth) depth->data[o] = std::isfinite(dmin) ? dmin : f_.max_dist;
            if (steps) steps->data[o] = st;
            if (normal) {
                const float len = glm::length(nsum);
                const glm::vec3 nn = (len > 1e-20f && std::isfinite(len)) ? nsum / len : glm::vec3(0.0f);
                for (int c = 0; c < 3; ++c) normal->data[o * 3 + c] = nn[c];
            }
        }
}

// The Prospero image of a 2D model: white inside (d < 0).
void Worker::render_tile_2d(int x0, int y0, int x1, int y1, Image& img, AovPlane* depth) {
    alignas(64) float x[kBatch], y[kBatch], z[kBatch] = {};
    const float sx = img.width > 1 ? 2.0f / static_cast<float>(img.width - 1) : 0.0f;
    const float sy = img.height > 1 ? 2.0f / static_cast<float>(img.height - 1) : 0.0f;
    for (int row = y0; row < y1; ++row)
        for (int c0 = x0; c0 < x1; c0 += kBatch) {
            const int m = std::min(kBatch, x1 - c0);
            for (int i = 0; i < m; ++i) {
                x[i] = -1.0f + sx * static_cast<float>(c0 + i);
                y[i] = 1.0f - sy * static_cast<float>(row);
            }
            float d[kBatch];
            if (f_.has_distance) {
                eval_leaf(0, x, y, z, m, d);
            } else {
                std::fill_n(d, m, 1.0f);
            }
            for (int i = 0; i < m; ++i) {
                const size_t o = static_cast<size_t>(row) * img.width + c0 + i;
                const float v = d[i] < 0.0f ? 1.0f : 0.0f;
                for (int c = 0; c < 3; ++c) img.pixels[o * 3 + c] = v;
                if (depth) depth->data[o] = std::isfinite(d[i]) ? d[i] : 0.0f;
            }
        }
}

// A Lipschitz estimate for a raw field over a box: the largest gradient norm (forward
// differences) on a 16^3 grid, among the tenth of the points with the smallest |f| (the far
// field of e.g. a polynomial grows much faster than near its surface, where steps matter),
// times 1.5.
float estimate_lipschitz(const CompiledScene& scene, const glm::vec3& lo, const glm::vec3& hi) {
    constexpr int kGrid = 16;
    Evaluator ev(scene.distance);
    const glm::vec3 ext = hi - lo;
    if (!std::isfinite(max3(ext))) return 1.0f;
    const float e = 1e-3f * std::max(max3(ext), 1e-6f);
    std::vector<float> fx, fy, fz, value, grad;
    for (int k = 0; k < kGrid; ++k)
        for (int j = 0; j < kGrid; ++j)
            for (int i = 0; i < kGrid; ++i) {
                const glm::vec3 p = lo + ext * (glm::vec3(i, j, k) + 0.5f) / static_cast<float>(kGrid);
                for (int q = 0; q < 4; ++q) {
                    fx.push_back(p.x + (q == 1 ? e : 0.0f));
                    fy.push_back(p.y + (q == 2 ? e : 0.0f));
                    fz.push_back(p.z + (q == 3 ? e : 0.0f));
                }
            }
    std::vector<float> out(fx.size());
    for (size_t i = 0; i < fx.size(); i += kBatch) {
        const int m = static_cast<int>(std::min<size_t>(kBatch, fx.size() - i));
        ev.eval(fx.data() + i, fy.data() + i, fz.data() + i, m, scene.time);
        std::copy_n(ev.output(0), m, out.data() + i);
    }
    std::vector<std::pair<float, float>> samples;  // (|f|, |grad f|)
    for (size_t i = 0; i + 3 < out.size(); i += 4) {
        const glm::vec3 g(out[i + 1] - out[i], out[i + 2] - out[i], out[i + 3] - out[i]);
        const float gn = glm::length(g) / e;
        if (std::isfinite(gn) && std::isfinite(out[i])) samples.emplace_back(std::fabs(out[i]), gn);
    }
    if (samples.empty()) return 1.0f;
    std::sort(samples.begin(), samples.end());
    float l = 0.0f;
    for (size_t i = 0; i < (samples.size() + 9) / 10; ++i) l = std::max(l, samples[i].second);
    return l > 1e-6f ? 1.5f * l : 1.0f;
}

}  // namespace

Image render(const CompiledScene& scene, const RenderOptions& options, RenderStats* stats) {
    Frame f(scene);
    const RenderSettings& rs = scene.render;
    f.width = std::max(rs.width, 1);
    f.height = std::max(rs.height, 1);
    f.cone = rs.aa == "cone";
    f.samples = f.cone ? 1 : std::clamp(rs.samples, 1, 4096);
    f.max_steps = std::max(rs.max_steps, 1);
    f.max_bounces = std::clamp(rs.max_bounces, 0, 64);
    f.eps = std::isfinite(rs.epsilon) && rs.epsilon > 0 ? rs.epsilon : 1e-4f;
    f.max_dist = std::isfinite(rs.max_distance) && rs.max_distance > 0 ? rs.max_distance : 100.0f;
    f.shadows = rs.shadows;
    f.ao = rs.ao;
    f.time = scene.time;
    f.view = options.view;
    f.ambient = glm::vec3(nonneg(scene.ambient.x), nonneg(scene.ambient.y), nonneg(scene.ambient.z));
    f.background = glm::vec3(nonneg(scene.background.x), nonneg(scene.background.y), nonneg(scene.background.z));
    f.has_distance = !scene.distance.outputs.empty();
    f.has_material = scene.shading.outputs.size() >= static_cast<size_t>(1 + kMatOut);
    f.raw = scene.raw_field && f.has_distance;
    if (f.raw) {
        f.cone = false;
        f.samples = std::clamp(rs.samples, 1, 4096);
    }
    if (f.raw && !scene.bounds.finite()) {
        // No bounds and no distance: march within the cube around the camera's target whose
        // half-size is the camera's distance to it (a .vm model's default view frames it).
        const float r = std::max(glm::length(scene.camera.position - scene.camera.target), 1.0f);
        f.lo = scene.camera.target - glm::vec3(r);
        f.hi = scene.camera.target + glm::vec3(r);
        f.clip = std::isfinite(r);
    } else if (scene.bounds.finite()) {
        // A little slack so rays start outside the surface's tolerance band.
        const glm::vec3 ext = scene.bounds.hi - scene.bounds.lo;
        const glm::vec3 margin = glm::vec3(1e-3f * std::max(max3(ext), 0.0f) + 1e-3f);
        f.lo = scene.bounds.lo - margin;
        f.hi = scene.bounds.hi + margin;
        f.clip = f.lo.x <= f.hi.x && f.lo.y <= f.hi.y && f.lo.z <= f.hi.z;
    } else if (!f.raw && !scene.half_spaces.empty()) {
        const Bounds& sb = scene.solid_bounds;
        const bool any = sb.lo.x <= sb.hi.x && sb.lo.y <= sb.hi.y && sb.lo.z <= sb.hi.z;
        const float margin = 1e-3f * (any ? std::max(max3(sb.hi - sb.lo), 0.0f) : 0.0f) + 1e-3f;
        f.solid_lo = any ? sb.lo - margin : glm::vec3(1.0f);
        f.solid_hi = any ? sb.hi + margin : glm::vec3(-1.0f);
        for (const glm::vec4& q : scene.half_spaces) f.planes.emplace_back(glm::vec3(q), q.w + margin + 1e-3f * std::fabs(q.w));
    }
    if (f.raw) {
        f.raw_lipschitz = estimate_lipschitz(scene, f.lo, f.hi);
        f.raw_max_step = f.clip ? glm::length(f.hi - f.lo) / 48.0f : 0.05f * f.max_dist;
    }
    for (int i = 0; i < f.samples; ++i) {
        const float sx = (static_cast<float>(i) + 0.5f) / static_cast<float>(f.samples);
        float sy = radical_inverse2(static_cast<uint32_t>(i)) + 0.5f / static_cast<float>(f.samples);
        if (sy >= 1.0f) sy -= 1.0f;
        f.offsets.emplace_back(sx, sy);
    }
    // Tiles hold ~256+ primary rays so the lane window stays full while rays finish.
    f.tile = f.samples <= 2 ? 16 : (f.samples <= 8 ? 8 : 4);

    // Acceleration: over-relaxation, clipping to the bounds (a raw field needs its box
    // anyway: it is where it is marched) and the tape tree (built below, in the arena).
    f.premarch = !f.raw && !f.cone;
    if (options.baseline) {
        f.relax = 1.0f;
        f.premarch = false;
        f.planes.clear();
        if (!f.raw) f.clip = false;
    }
    f.tree.init_full(scene.distance);
    glm::vec3 root_lo(0.0f), root_hi(0.0f);
    bool want_tree = !options.baseline && f.has_distance && !scene.is_2d && scene.distance.code.size() >= kTreeMinProgram;
    if (want_tree) {
        // Around the region rays can reach: the (clip) box with room for normal and AO taps,
        // else a cube around the camera of twice the ray length, cut to the finite sides of
        // the bounds. Points outside run the full program (leaf 0).
        constexpr float kPad = 0.25f;
        if (f.clip) {
            const float pad = kPad + 0.05f * max3(f.hi - f.lo);
            root_lo = f.lo - pad;
            root_hi = f.hi + pad;
        } else {
            const float R = 2.0f * f.max_dist;
            root_lo = scene.camera.position - R;
            root_hi = scene.camera.position + R;
            for (int a = 0; a < 3; ++a) {
                if (scene.bounds.lo[a] > -1e29f) root_lo[a] = std::max(root_lo[a], scene.bounds.lo[a] - kPad);
                if (scene.bounds.hi[a] < 1e29f) root_hi[a] = std::min(root_hi[a], scene.bounds.hi[a] + kPad);
            }
        }
        for (int a = 0; a < 3; ++a) want_tree &= std::isfinite(root_lo[a]) && std::isfinite(root_hi[a]) && root_lo[a] < root_hi[a];
    }
    if (f.has_material) f.shade_code = live_code(scene.shading, 1);

    Image img(f.width, f.height, 3);
    AovPlane *depth = nullptr, *normal = nullptr, *steps = nullptr;
    img.aovs.reserve(options.aovs.size());
    for (const std::string& name : options.aovs) {
        if (std::find(known_aovs().begin(), known_aovs().end(), name) == known_aovs().end())
            throw std::invalid_argument("unknown AOV '" + name + "' (known: depth, normal, steps)");
        if (img.aov(name)) continue;
        const int ch = name == "normal" ? 3 : 1;
        img.aovs.push_back(AovPlane{name, ch, std::vector<float>(static_cast<size_t>(f.width) * f.height * ch, 0.0f)});
    }
    for (auto& a : img.aovs) {
        if (a.name == "depth") depth = &a;
        if (a.name == "normal") normal = &a;
        if (a.name == "steps") steps = &a;
    }
    f.want_depth = depth != nullptr;
    f.want_normal = normal != nullptr;
    f.want_steps = steps != nullptr;

    const int tx = (f.width + f.tile - 1) / f.tile, ty = (f.height + f.tile - 1) / f.tile;
    const int total = tx * ty;
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    auto seconds = [&](clock::time_point t) { return std::chrono::duration<double>(t - start).count(); };
    std::atomic<int> tiles_done{0};
    std::atomic<int64_t> last_report{0};  // ns since start
    std::mutex report;
    auto progress = [&](int done) {
        if (!options.progress) return;
        const auto now = clock::now();
        const int64_t ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now - start).count();
        if (ns - last_report.load(std::memory_order_relaxed) < 100'000'000) return;
        if (!report.try_lock()) return;
        if (ns - last_report.load(std::memory_order_relaxed) >= 100'000'000) {
            last_report.store(ns, std::memory_order_relaxed);
            options.progress(RenderProgress{done, total, seconds(now)});
        }
        report.unlock();
    };

    tbb::enumerable_thread_specific<std::unique_ptr<Worker>> workers;
    auto body = [&](const tbb::blocked_range<int>& range) {
        std::unique_ptr<Worker>& w = workers.local();
        if (!w) w = std::make_unique<Worker>(f);
        for (int t = range.begin(); t != range.end(); ++t) {
            const int x0 = (t % tx) * f.tile, y0 = (t / tx) * f.tile;
            const int x1 = std::min(x0 + f.tile, f.width), y1 = std::min(y0 + f.tile, f.height);
            if (scene.is_2d) w->render_tile_2d(x0, y0, x1, y1, img, depth);
            else w->render_tile(x0, y0, x1, y1, img, depth, normal, steps);
            progress(tiles_done.fetch_add(1, std::memory_order_relaxed) + 1);
        }
    };
    const int threads = options.threads > 0 ? options.threads : tbb::task_arena::automatic;
    tbb::task_arena arena(threads);
    double tree_ms = 0.0;
    arena.execute([&] {
        if (want_tree) {
            const auto t0 = clock::now();
            build_tree(f.tree, scene.distance, root_lo, root_hi, f.time, !f.raw,
                       static_cast<size_t>(f.width) * static_cast<size_t>(f.height) * static_cast<size_t>(f.samples));
            tree_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
        }
        f.regs.num_regs = std::max<uint32_t>(f.tree.max_regs, std::max<uint32_t>(scene.distance.num_regs, 1));
        tbb::parallel_for(tbb::blocked_range<int>(0, total, 1), body);
    });
    if (options.progress) options.progress(RenderProgress{total, total, seconds(clock::now())});

    if (stats) {
        *stats = RenderStats{};
        for (auto& w : workers)
            if (w) {
                stats->distance_points += w->stats.distance_points;
                for (int k = 0; k < RenderStats::kKinds; ++k) stats->distance_points_by[k] += w->stats.distance_points_by[k];
                stats->shading_points += w->stats.shading_points;
                stats->primary_rays += w->stats.primary_rays;
                stats->distance_instructions += w->stats.distance_instructions;
                stats->shading_instructions += w->stats.shading_instructions;
                stats->skips += w->stats.skips;
            }
        stats->tree_leaves = f.tree.active ? f.tree.leaves.size() - 1 : 0;
        stats->interval_boxes = f.tree.boxes;
        stats->tree_ms = tree_ms;
    }
    return img;
}

}  // namespace sdfc
