// The marches of a Worker: the lane-window loop (run) that every kind of ray goes through,
// and what each kind does with its distances. Design:
//
//  * Marching: a ray hits when d < epsilon * max(t, 1) (t = path length from the eye, so the
//    tolerance grows with distance like the pixel footprint, but never below epsilon); it
//    misses when t passes max_distance or the scene's bounding box. A ray that runs out of
//    max_steps counts as a hit if it is within one pixel footprint of the surface, else a
//    miss. NaN distances end the ray as a miss, +inf steps to the end, -inf is a hit. A hit
//    point moves on by its last distance d (still outside for a 1-Lipschitz bound).
//  * Over-relaxed sphere tracing (Keinert et al. 2014, omega = 1.5 falling back to 1 when
//    consecutive unbounding spheres stop overlapping) for camera, secondary and hard shadow
//    rays: fewer steps, same hits for any 1-Lipschitz bound.
//  * Shadows: hard (a march toward the light, any hit = 0) when radius == 0, else soft:
//    Quilez's penumbra estimate with the closest-approach refinement (h, previous h) and the
//    inner/outer-penumbra form: res = min(d_closest / (w * t)), marching through occluders,
//    vis = 0.25 (1 + res)^2 (2 - res) for res in [-1, 1]. w = radius / distance for point
//    lights, w = radius (tangent of the angular radius) for directional ones. Soft shadow
//    rays are over-relaxed too, but only where d >= 4 w t (far from any penumbra).
//  * Cone tracing (aa == "cone"): the cone's radius is the pixel footprint r(t). Where the
//    ray passes an edge (d < r without hitting), the closest approach (smallest d/r) is
//    recorded as a partial hit of coverage 1 - d/r; up to 4 such layers are composited front
//    to back, then the final hit (or the background) gets the remaining weight.
//  * Raw fields (CompiledScene::raw_field, .vm models, no distance bound): see march_raw();
//    sign-change marching with refinement, hard shadows only, no AO, no cone tracing. A
//    field that touches zero without going below (a sheet of zero thickness, which
//    coincident faces of a CSG model leave) has no sign change: where the tree proves it
//    not negative, rays jump as over empty space (tape_tree.hpp kSheet, segment_bounds).
//  * Tape tree: lanes evaluate their leaf's tape and jump over leaves proven empty
//    (tape_tree.hpp); each march decides whether a jump is safe for it (its `skip`).
//
// Each march keeps its per-lane state in the slots a, b, w, om, pr, sl: the table of what
// each slot holds for each march is at struct Lanes (lanes.hpp).
//
// FP exceptions are never unmasked here, so GCC may if-convert float compares: the lane
// update loops below vectorise only with this.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include <algorithm>
#include <cmath>

#include "runtime/cpu/worker.hpp"

namespace sdfc::cpu {

// Lanes [0, n) whose point left their cached leaf box find their leaf.
// Then returns in L.idx[0, return) the lanes that may jump (empty leaf for their sign).
inline int Worker::locate_lanes(Lanes& L, int n) {
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
    L.relocate(L.idx, m, T_);
    for (int i = 0; i < n; ++i) out[i] = L.slo(i) > 0.0f;
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
void Worker::retire(Lanes& L, int& n, Finish&& finish) {
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
// with an empty [tmin, tmax] go to `empty(r)` without an evaluation, and so do rays whose
// columns (cols_, a raw field's) hold no run before their end; the others start at their
// first run (a raw march's first sample there, with no previous one, decides as one after a
// jump would: a sign change is a hit at it, no secant from before).
// With a tape tree, a lane whose leaf is empty for it (signed lower bound slo > 0) may
// jump: `skip(L, i, slo, t_exit)` decides (and sets L.t[i] and any state) or returns
// false; a ray that jumps past tmax ends through `out(L, i)` (which sets a miss) and
// `finish`. t_exit is where the ray leaves the leaf's box, or tmax if that comes first
// (nothing beyond tmax is ever sampled).
// `segments`: lanes in leaves that are not empty also jump where the field is proven
// positive along their way through the leaf (segment_bounds).
template <class Init, class Update, class Finish, class Empty, class Skip, class Out>
void Worker::run(const RaySet& rs, Init&& init, Update&& update, Finish&& finish, Empty&& empty, Skip&& skip, Out&& out,
                 bool segments) {
    Lanes& L = *lanes_;
    int n = 0;
    size_t next = 0;
    const size_t count = rs.size();
    const bool tree = T_.active;
    uint32_t hint = 0;  // the leaf of the ray loaded last
    for (;;) {
        while (n < kWindow && next < count) {
            const uint32_t r = static_cast<uint32_t>(next++);
            if (!(rs.tmin[r] <= rs.tmax[r])) {
                empty(r);
                continue;
            }
            // With columns (a raw field's: no sign change before a column's first run), the
            // ray starts at its first run, and one with none before its end is not marched.
            uint32_t place = 0;
            const float start = cols_ ? cols_->first_run(rs.o(r), rs.d(r), rs.tmin[r], rs.tmax[r], place) : rs.tmin[r];
            if (!(start <= rs.tmax[r])) {
                empty(r);
                continue;
            }
            L.load(n, rs, r, f_.relax);
            L.place[n] = place;
            L.t[n] = std::max(L.t[n], start);
            init(L, n);
            if (tree) {
                // Its first leaf from the one before's: the rays come in pixel order, so their
                // points are nearly always in that leaf or one nearby (a short walk from its
                // neighbour instead of the whole way down from the root).
                const float px = L.ox[n] + L.t[n] * L.dx[n], py = L.oy[n] + L.t[n] * L.dy[n], pz = L.oz[n] + L.t[n] * L.dz[n];
                hint = T_.locate_from(hint, px, py, pz);
                L.set_leaf(n, hint, T_.leaves[hint]);
            }
            ++n;
        }
        if (n == 0) return;
        for (int i = 0; i < n; ++i) {
            L.x[i] = L.ox[i] + L.t[i] * L.dx[i];
            L.y[i] = L.oy[i] + L.t[i] * L.dy[i];
            L.z[i] = L.oz[i] + L.t[i] * L.dz[i];
        }
        if (tree) {
            // Lanes in leaves empty for them jump, all lanes one jump at a time (each lane's
            // jumps depend on each other: the lanes' tree walks overlap instead of waiting).
            int nc = locate_lanes(L, n);
            bool any_out = false;
            // Lanes to bound next: all of them the first time, then only those that landed
            // in a leaf not empty for them since (no other lane's leaf or state changes).
            bool scanned = false;
            int np = 0;
            alignas(64) int32_t pend[kWindow];
            auto bound = [&] {
                const int r = scanned ? segment_bounds(L, pend, np) : segment_bounds(L, nullptr, n);
                scanned = true, np = 0;
                return r;
            };
            if (segments && nc == 0) nc = bound();
            for (int it = 0; nc > 0 && it < 64; ++it) {
                int moved = 0;
                for (int j = 0; j < nc; ++j) {
                    const int i = L.idx[j];
                    const bool through = L.seg[i] > -INFINITY;  // (segment_bounds proved its way)
                    if (!jump(L, i, skip)) continue;
                    ++stats.skips;
                    stats.segment_skips += through;
                    if (!(L.t[i] <= L.tmax[i])) {
                        out(L, i);
                        L.done[i] = 1;
                        any_out = true;
                        continue;
                    }
                    L.x[i] = L.ox[i] + L.t[i] * L.dx[i];
                    L.y[i] = L.oy[i] + L.t[i] * L.dy[i];
                    L.z[i] = L.oz[i] + L.t[i] * L.dz[i];
                    L.idx[moved++] = i;
                }
                L.relocate(L.idx, moved, T_);
                nc = 0;
                for (int j = 0; j < moved; ++j) {
                    const int i = L.idx[j];
                    const bool jumps = L.slo(i) > 0.0f;
                    L.idx[nc] = i;
                    nc += jumps;
                    pend[np] = i;
                    np += scanned & !jumps;  // (a lane that jumps again is pending after that)
                }
                if (segments && nc == 0) nc = bound();
            }
            if (segments)
                for (int i = 0; i < n; ++i) L.seg[i] = -INFINITY;  // (each holds from its t only)
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

// Lane i's jump out of its empty leaf, as `skip` decides (see run). A ray outside solids
// first tries the leaf's biggest empty ancestor (Leaf::up), whose box it leaves farther on,
// with that box's lower bound: one jump instead of one per leaf on the way (showcase.sdf:
// 88 % of the jumps left a leaf whose parent was empty too). Not where that bound would
// put the last over-relaxed step in doubt (skip_sphere's rewind): the leaf's own bound
// decides that.
template <class Skip>
bool Worker::jump(Lanes& L, int i, Skip& skip) {
    const float te = std::min(L.exit_t(i), L.tmax[i]);
    const TapeTree::Leaf& lf = T_.leaves[L.leaf[i]];
    if (L.sign[i] > 0.0f && lf.up != lf.node) {
        const TapeTree::NodeBox& B = T_.boxes_[lf.up];
        const float ta = std::min(L.exit_t(i, B.lo, B.hi), L.tmax[i]);
        if (ta > te && !L.relaxed_doubt(i, B.elo) && skip(L, i, B.elo, ta)) return true;
    }
    return skip(L, i, L.slo(i), te);
}

// The jump of an (over-relaxed) sphere-traced lane in an empty leaf: only if no point of
// the leaf could stop the ray (slo >= its hit threshold up to the landing point). Lands
// slo beyond the box's exit: the exit point is in the box, so its distance is >= slo.
// If the check of the last over-relaxed step is not sure to pass (r >= slo is all we
// know), it is treated as failed instead, without an evaluation: back to the previous
// sphere's boundary, omega = 1 (as march() does), and the jump is decided from there.
inline bool Worker::skip_sphere(Lanes& L, int i, float slo, float te) {
    if (L.relaxed_doubt(i, slo)) {
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

// The lane update of over-relaxed sphere tracing (rules.h sdf_relaxed_step) on sign * d,
// for camera and bounce rays and (strict) hard shadow rays; `a` keeps the value the hit test
// (sdf_relaxed_hit) reads.
namespace {
auto relaxed_update(int max_steps, float eps, bool strict) {
    return [=](Lanes& L, int m, const float* d) {
        for (int i = 0; i < m; ++i) {
            const int st = ++L.steps[i];
            float last;
            L.done[i] = rules::sdf_relaxed_step(L.sign[i] * d[i], L.t0[i], L.tmax[i], strict, st, max_steps, eps, L.t[i], L.om[i],
                                                L.pr[i], L.sl[i], last);
            L.a[i] = last;
        }
    };
}
}  // namespace

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
        relaxed_update(max_steps, eps, false),
        [&](Lanes& L, int i) {
            const uint32_t r = L.ray[i];
            const float s = L.a[i], path = L.t0[i] + L.t[i];
            steps_[r] = L.steps[i];
            hit_[r] = rules::sdf_relaxed_hit(s, path, L.steps[i], max_steps, eps, f_.camera.footprint_base(), f_.camera.footprint_slope());
            t_[r] = rules::sdf_hit_t(L.t[i], s, hit_[r]);
        },
        [&](uint32_t r) { t_[r] = rs.tmax[r]; },
        [&](Lanes& L, int i, float slo, float te) { return skip_sphere(L, i, slo, te); },
        [](Lanes& L, int i) { L.a[i] = INFINITY, L.t[i] = L.tmax[i]; });
}

// Marching a raw field (no distance bound): steps of |f| / L, with L a Lipschitz estimate
// sampled over the volume (make_frame, frame.cpp), clamped to [one pixel footprint,
// raw_max_step], or, for camera rays where the field falls, to just past the zero the last
// two samples' secant predicts (at most twice that step), and twice that step for shadow rays
// where it rises; a sign change (f <= 0) is refined to the outside end of the bracket, on the
// chord first (rules.h sdf_raw_step). Thin features (under a step or two, or where the
// estimate is low) can be missed: the price of no bound. An empty tape-tree leaf is left by
// the same rule, its lower bound standing for the sample.
// Lane state: a = previous t (the bracket's outside end), pr = its value (NaN: unknown),
// w / b = the bracket's inside end and its value, sl = refinements (0 while marching),
// om = 1 when the ray ended as a hit.
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
    const float inv_l = 1.0f / f_.raw_lipschitz;
    const float foot_base = f_.camera.footprint_base(), foot_slope = f_.camera.footprint_slope();
    const RayColumns* cols = cols_;
    run(
        rs, [](Lanes& L, int i) { L.a[i] = -1.0f, L.pr[i] = NAN, L.sl[i] = 0.0f, L.om[i] = 0.0f; },
        [&](Lanes& L, int m, const float* dist) {
            // Sign-change marching with refinement (rules.h sdf_raw_step): a = previous t
            // (the bracket's outside end), pr = its value, w / b = the inside end and its
            // value, sl = refinements, om = 1 when the ray ended as a hit.
            for (int i = 0; i < m; ++i) {
                const int st = ++L.steps[i];
                bool hit;
                L.done[i] = rules::sdf_raw_step(L.sign[i] * dist[i], L.t0[i], L.tmax[i], shadow, st, max_steps, f_.eps, foot_base,
                                                foot_slope, inv_l, f_.raw_max_step, L.t[i], L.a[i], L.pr[i], L.w[i], L.b[i], L.sl[i],
                                                hit);
                L.om[i] = hit ? 1.0f : 0.0f;
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
        [&](Lanes& L, int i, float slo, float te) {
            // No sign change in an empty leaf: past its exit, by the step a sample of value
            // slo would take (the field is >= slo at the exit, which lies in the leaf), but
            // at least a quarter pixel, for progress; the current point is the outside end
            // of a later bracket.
            if (L.sl[i] > 0.0f) return false;  // refining
            const float t = L.t[i], tn = std::max(te, t);
            L.a[i] = t, L.pr[i] = NAN;  // (not evaluated: no secant from it)
            const float beyond = std::min(slo * inv_l, f_.raw_max_step);
            L.t[i] = tn + std::max(beyond, 0.25f * f_.footprint(L.t0[i] + tn) + 1e-6f * tn);
            if (cols) {
                // Nothing before the column's next run can change sign: the ray lands there,
                // which is then the bracket's outside end too.
                const float c = cols->clear_until(glm::vec3(L.ox[i], L.oy[i], L.oz[i]), glm::vec3(L.dx[i], L.dy[i], L.dz[i]), tn, L.tmax[i], L.place[i]);
                if (c > L.t[i]) L.t[i] = c, L.a[i] = c, ++stats.column_skips;
            }
            return true;
        },
        [](Lanes& L, int i) { L.om[i] = 0.0f, L.t[i] = L.tmax[i]; }, T_.active);
}

// Where the field along a lane's way through its leaf (from t to the exit, or tmax) is
// proven positive, the lane can leave the leaf as if it were empty: its leaf's tape over the
// box around that segment, in interval arithmetic (a segment's box is much smaller than the
// leaf's, and a ray leaving a surface, or passing one, often clears it). Once per lane and
// leaf, for lanes not refining whose leaves are not empty; by leaf, kIvLanes boxes a call.
// For the lanes lanes[0, n) (lanes [0, n) when null). Sets L.seg of the lanes proven and
// returns them in L.idx[0, return).
// Only for leaves of at most kSegmentTape instructions: over a long tape (bear.vm's leaves
// keep 517 of its 525 instructions, exp and log among them) a bound costs more than the
// steps it saves (3.1x the time).
constexpr uint32_t kSegmentTape = 64;

int Worker::segment_bounds(Lanes& L, const int32_t* lanes, int n) {
    int m = 0;
    for (int j = 0; j < n; ++j) {
        const int i = lanes ? lanes[j] : j;
        const bool want = L.tested[i] != L.leaf[i] && L.leaf[i] != 0 && L.sl[i] == 0.0f && !(L.slo(i) > 0.0f) &&
                          T_.leaves[L.leaf[i]].len <= kSegmentTape;
        L.idx[m] = i;
        m += want;
    }
    if (m == 0) return 0;
    if (!seg_iv_) seg_iv_ = std::make_unique<IntervalEvaluator>(T_.max_regs, 64);
    alignas(64) uint32_t leaf[kWindow];
    for (int j = 0; j < m; ++j) leaf[j] = L.leaf[L.idx[j]], L.tested[L.idx[j]] = L.leaf[L.idx[j]];
    Buckets& B = *buckets_;
    B.build(leaf, m);
    alignas(64) int32_t lane[kWindow];
    std::copy_n(L.idx, m, lane);
    alignas(64) float bx[6][kIvLanes];
    int proven = 0;
    for (int b = 0; b < B.nb; ++b) {
        const TapeTree::Leaf& lf = T_.leaves[B.key_of[b]];
        for (int j0 = B.start[b]; j0 < B.start[b + 1]; j0 += kIvLanes) {
            const int c = std::min(kIvLanes, B.start[b + 1] - j0);
            for (int q = 0; q < c; ++q) {
                const int i = lane[B.order[j0 + q]];
                const float ta = L.t[i], tb = std::max(std::min(L.exit_t(i), L.tmax[i]), ta);
                const float o[3] = {L.ox[i], L.oy[i], L.oz[i]}, d[3] = {L.dx[i], L.dy[i], L.dz[i]};
                for (int k = 0; k < 3; ++k) {
                    const float a = o[k] + ta * d[k], e = o[k] + tb * d[k];
                    bx[2 * k][q] = std::max(std::min(a, e), lf.lo[k]);
                    bx[2 * k + 1][q] = std::min(std::max(a, e), lf.hi[k]);
                }
            }
            seg_iv_->eval(lf.view(), bx[0], bx[1], bx[2], bx[3], bx[4], bx[5], c, f_.time);
            for (int q = 0; q < c; ++q) {
                const int i = lane[B.order[j0 + q]];
                const Interval r = seg_iv_->result(q);
                const float lo = raw_floor(L.sign[i] > 0.0f ? r.lo : -r.hi, L.sign[i] > 0.0f ? r.hi : -r.lo);  // (a sheet at most: empty)
                if (lo > 0.0f) L.seg[i] = lo, L.idx[proven++] = i;
            }
        }
    }
    return proven;
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
    const float foot_base = f_.camera.footprint_base(), foot_slope = f_.camera.footprint_slope();
    // A partial hit the rules recorded (as event ev_n_[r] - 1).
    auto store = [&](uint32_t r, bool emitted, float et, float ew) {
        if (emitted) ev_t_[r * kConeEvents + ev_n_[r] - 1] = et, ev_w_[r * kConeEvents + ev_n_[r] - 1] = ew;
    };
    auto emit = [&](uint32_t r, float t, float coverage) {
        bool emitted;
        float et, ew;
        rules::sdf_cone_emit(coverage, t, trans_[r], ev_n_[r], emitted, et, ew);
        store(r, emitted, et, ew);
    };
    // Lane state: a = smallest d / r in the current edge zone (>= 1: none), b = its t,
    // w = 1 when the final state is a hit (rules.h sdf_cone_step).
    run(
        rs, [](Lanes& L, int i) { L.a[i] = 2.0f; },
        [&](Lanes& L, int m, const float* dist) {
            for (int i = 0; i < m; ++i) {
                const uint32_t r = L.ray[i];
                const int st = ++L.steps[i];
                bool emitted, hit;
                float et, ew;
                L.done[i] = rules::sdf_cone_step(dist[i], L.t0[i], L.tmax[i], st, max_steps, f_.eps, foot_base, foot_slope, L.t[i],
                                                 L.a[i], L.b[i], trans_[r], ev_n_[r], emitted, et, ew, hit);
                store(r, emitted, et, ew);
                L.w[i] = hit ? 1.0f : 0.0f;
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

// Hard shadows: vis_[i] = 0 if the segment hits anything, else 1.
void Worker::shadow_hard(const RaySet& rs) {
    vis_.assign(rs.size(), 1.0f);
    const int max_steps = f_.max_steps;
    const float eps = f_.eps;
    run(
        rs, [](Lanes&, int) {},
        relaxed_update(max_steps, eps, true),  // a blocker counts only at a safe point (inside an occluder is one)
        [&](Lanes& L, int i) {
            const float d = L.a[i], path = L.t0[i] + L.t[i];
            const bool blocked =
                rules::sdf_relaxed_hit(d, path, L.steps[i], max_steps, eps, f_.camera.footprint_base(), f_.camera.footprint_slope());
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
            // Quilez's penumbra with the closest-approach refinement, over-relaxed far from
            // any penumbra (rules.h sdf_soft_step): a = res, b = the previous positive distance.
            for (int i = 0; i < m; ++i) {
                const int st = ++L.steps[i];
                L.done[i] = rules::sdf_soft_step(dist[i], L.t0[i], L.tmax[i], L.w[i], st, max_steps, eps, L.t[i], L.a[i], L.b[i],
                                                 L.om[i], L.pr[i], L.sl[i]);
            }
        },
        [&](Lanes& L, int i) {
            vis_[L.ray[i]] = rules::sdf_penumbra(L.a[i]);
        },
        [](uint32_t) {},
        [&](Lanes& L, int i, float slo, float te) {
            if (L.relaxed_doubt(i, slo)) {  // as in skip_sphere()
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

// The cone around a tile's primary rays (rules.h sdf_tile_cone: axis o + t d, radius
// r.x + r.y t) and the t where its pre-march begins (sdf_premarch_begin).
float Worker::tile_cone(int x0, int y0, int x1, int y1, glm::vec3& o, glm::vec3& d, glm::vec2& r) const {
    rules::sdf_tile_cone(f_.camera.rule_camera(), static_cast<float>(x0), static_cast<float>(y0), static_cast<float>(x1),
                         static_cast<float>(y1), o, d, r);
    return f_.clip && f_.planes.empty() ? rules::sdf_premarch_begin(f_.lo, f_.hi, o, d, r, f_.max_dist) : 0.0f;
}

// Tile cone pre-marching: one march along the tile's central ray for all its primary rays
// (rules.h sdf_tile_cone, sdf_premarch_step: why it is safe); they start at the final t.
float Worker::tile_start(int x0, int y0, int x1, int y1) {
    glm::vec3 o, d;
    glm::vec2 r;
    float t = tile_cone(x0, y0, x1, y1, o, d, r);
    for (int i = 0; i < 32 && t < f_.max_dist; ++i) {
        const glm::vec3 p = o + d * t;
        float dist;
        eval_points(&p.x, &p.y, &p.z, 1, &dist);
        if (!rules::sdf_premarch_step(dist, r, f_.eps, t)) break;
    }
    return t;
}

// The same for a raw field (no distance to march on), with its tape tree: the tile's cone
// moves on along its axis leaf by leaf while every leaf that the cone's box over the step
// meets is proven empty (the field positive all over it), so no ray of the tile can see a
// sign change before the final t. A 16 x 16 tile's rays then skip together what they would
// each have left by a jump per leaf (colonnade.vm at 1024^2: 22.2 -> 14.9 jumps a pixel,
// 0.89x the time, the same picture).
float Worker::tile_start_raw(int x0, int y0, int x1, int y1) {
    if (!T_.active) return 0.0f;
    glm::vec3 o, d;
    glm::vec2 r;
    float t = tile_cone(x0, y0, x1, y1, o, d, r);
    for (int i = 0; i < 64 && t < f_.max_dist; ++i) {
        const glm::vec3 p = o + d * t;
        const uint32_t id = T_.locate(p.x, p.y, p.z);
        const TapeTree::Leaf& L = T_.leaves[id];
        if (id == 0 || !(L.ivlo > 0.0f)) break;
        float ts = t, te = INFINITY;  // te: where the axis leaves the leaf's box
        rules::sdf_clip_box(glm::vec3(L.lo[0], L.lo[1], L.lo[2]), glm::vec3(L.hi[0], L.hi[1], L.hi[2]), o, d, ts, te);
        // A little past the exit (so that the next lookup finds the next leaf), covered by
        // the margin of the box checked: every ray's point at any t' in [t, tn] is within
        // r(t') of the axis's, which is on the segment [p, q].
        const float step = 1e-3f * rules::sdf_max3(glm::vec3(L.hi[0], L.hi[1], L.hi[2]) - glm::vec3(L.lo[0], L.lo[1], L.lo[2]));
        const float tn = std::min(std::max(te, t) + step, f_.max_dist);
        if (!(tn > t)) break;
        const glm::vec3 q = o + d * tn;
        const float g = r.x + r.y * tn;
        if (!T_.all_empty(glm::min(p, q) - g, glm::max(p, q) + g)) break;
        t = tn;
        ++stats.tile_skips;
    }
    return t;
}

// A raw field's shadow rays toward one light (one tile's hits): the last part of every
// segment, from the fraction u of its length on, lies in the box around the points at u and
// the segments' ends; where the tree proves that box empty, no ray can meet a sign change
// there, so each segment is cut at u (a ray that reaches the cut sees the light). u halves
// from 1 while the box stays empty. Rays clipped to the scene's box only (their ends are then
// inside the tree's root). Rays leaving the surface otherwise cross one leaf after another,
// each bigger than the last (colonnade.vm at 1024^2: 14.9 -> 8.7 jumps a pixel, 0.91x the
// time, the same picture).
void Worker::raw_shadow_cut(RaySet& rs) {
    const size_t n = rs.size();
    if (!T_.active || !f_.clip || !f_.planes.empty() || n == 0) return;
    auto empty_from = [&](float u) {
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (size_t r = 0; r < n; ++r) {
            const glm::vec3 o = rs.o(r), d = rs.d(r);
            const glm::vec3 a = o + d * (u * rs.tmax[r]), e = o + d * rs.tmax[r];
            lo = glm::min(lo, glm::min(a, e));
            hi = glm::max(hi, glm::max(a, e));
        }
        // (a margin over the rounding of the marches' own sample points)
        const float g = 1e-5f * (1.0f + std::max(rules::sdf_max3(glm::abs(lo)), rules::sdf_max3(glm::abs(hi))));
        return T_.all_empty(lo - g, hi + g);
    };
    float cut = 2.0f;
    for (float u = 1.0f; u >= 1.0f / 1024.0f && empty_from(u); u *= 0.5f) cut = u;
    if (cut > 1.0f) return;
    ++stats.shadow_cuts;
    for (size_t r = 0; r < n; ++r) rs.tmax[r] = std::max(rs.tmin[r], cut * rs.tmax[r]);
}

}  // namespace sdfc::cpu
