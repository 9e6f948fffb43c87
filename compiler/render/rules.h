// The per-ray rules of both renderers, written once in the subset where C++ with GLM and
// GLSL agree. The CPU tracer (runtime/cpu/) includes this file and calls the rules per
// lane; the build embeds the same text into every shader (compiler/glsl/glsl.cpp turns it
// into GLSL: the `#ifdef __cplusplus` blocks go, SDF_FN is dropped, SDF_INOUT(T) becomes
// `inout T`, SDF_OUT(T) `out T`, SDF_AND / SDF_OR `&&` / `||`). Schedulers differ (ray
// wavefronts on the CPU, a state machine around one map() call in GLSL); the rules may not.
//
// What stays inside the subset: float literals with an `f` suffix (GLSL ES 3.00 reads them;
// C++ then stays in float), explicit int -> float conversions, ?: and SDF_AND / SDF_OR on
// comparisons in the rules the lane loops run (bitwise in C++: branch-free, so they
// vectorise; measured: && there cost three-tori 10 %), no arrays, no constructors (C++
// aggregates and GLSL structs are filled field by field), every input a parameter (the
// GLSL passes its SDF_ constants, the CPU its RenderPlan's fields).
#ifdef __cplusplus
#pragma once
#include <glm/glm.hpp>
namespace sdfc::rules {
using namespace glm;  // the GLSL names: vec3, dot, normalize, clamp, max, ...
#define SDF_FN inline
#define SDF_INOUT(T) T&
#define SDF_OUT(T) T&
// `and` / `or` of comparisons that the CPU's lane loops evaluate without branches (bitwise
// on bools, so they vectorise); && and || in GLSL, which has no bitwise operators on bools.
#define SDF_AND &
#define SDF_OR |
#endif

// ---- numbers ----
SDF_FN float sdf_inf() { return uintBitsToFloat(0x7f800000u); }
SDF_FN bool sdf_finite(float v) { return !isnan(v) && !isinf(v); }
SDF_FN bool sdf_finite3(vec3 v) { return sdf_finite(v.x) && sdf_finite(v.y) && sdf_finite(v.z); }
SDF_FN float sdf_max3(vec3 v) { return max(v.x, max(v.y, v.z)); }
SDF_FN float sdf_maxabs3(vec3 v) { return max(abs(v.x), max(abs(v.y), abs(v.z))); }
SDF_FN float sdf_nonneg(float v) { return v > 0.0f ? (sdf_finite(v) ? v : 1e30f) : 0.0f; }  // NaN -> 0
SDF_FN float sdf_clamp01(float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; }
SDF_FN vec3 sdf_nonneg3(vec3 v) {
    vec3 r;
    r.x = sdf_nonneg(v.x);
    r.y = sdf_nonneg(v.y);
    r.z = sdf_nonneg(v.z);
    return r;
}

// ---- anti-aliasing ----
// Where sample i of n lies in its pixel: x stratified, y the base-2 radical inverse of i
// shifted by half a stratum (a Hammersley set).
SDF_FN vec2 sdf_sample_offset(int i, int n) {
    uint b = uint(i);
    b = (b << 16u) | (b >> 16u);
    b = ((b & 0x55555555u) << 1u) | ((b & 0xAAAAAAAAu) >> 1u);
    b = ((b & 0x33333333u) << 2u) | ((b & 0xCCCCCCCCu) >> 2u);
    b = ((b & 0x0F0F0F0Fu) << 4u) | ((b & 0xF0F0F0F0u) >> 4u);
    b = ((b & 0x00FF00FFu) << 8u) | ((b & 0xFF00FF00u) >> 8u);
    float sy = float(b) * 2.3283064365386963e-10f + 0.5f / float(n);
    if (sy >= 1.0f) sy -= 1.0f;
    vec2 r;
    r.x = (float(i) + 0.5f) / float(n);
    r.y = sy;
    return r;
}

// ---- tolerances along a ray ----
// Hit threshold at path length `path` (relative beyond one unit), the radius of one pixel's
// footprint (cone tracing, and "close enough" for rays out of steps), and the offset that
// takes a secondary ray off its surface (4 thresholds plus what floats at p resolve).
SDF_FN float sdf_thr(float eps, float path) { return eps * max(path, 1.0f); }
SDF_FN float sdf_footprint(float foot_base, float foot_slope, float path) { return foot_base + foot_slope * path; }
SDF_FN float sdf_bias(float eps, vec3 p, float path) { return 4.0f * sdf_thr(eps, path) + 2e-5f * (1.0f + sdf_maxabs3(p)); }

// ---- sphere tracing ----
// Over-relaxed sphere tracing (Keinert et al. 2014: omega = relax while consecutive
// unbounding spheres overlap; when they do not, or the step went through the surface
// (s < 0, camera rays), back to the previous sphere's boundary and omega = 1), on the signed
// value s at t. Steps are plain near a surface (s within 8 hit thresholds) so that grazing
// rays are sampled where plain tracing samples them, and a relaxed step past tmax is not
// taken: only a plain step may end the ray. `strict`: shadow rays, which end at t >= tmax
// (camera and bounce rays at t > tmax). `steps` counts this step. Returns true when the
// march is over; `last` is what sdf_relaxed_hit reads (inf after a failed relaxed step).
SDF_FN bool sdf_relaxed_step(float s, float t0, float tmax, bool strict, int steps, int max_steps, float eps,
                             SDF_INOUT(float) t, SDF_INOUT(float) om, SDF_INOUT(float) pr, SDF_INOUT(float) sl,
                             SDF_OUT(float) last) {
    float r = abs(s);
    float thr = sdf_thr(eps, t0 + t);
    bool fail = (om > 1.0f) SDF_AND (sl > pr) SDF_AND ((r + pr < sl) SDF_OR ((!strict) SDF_AND (s < 0.0f)));
    float tr = t + om * s;
    float w = ((s > 8.0f * thr) SDF_AND (strict ? tr < tmax : tr <= tmax)) ? om : 1.0f;
    float step = fail ? pr - sl : w * s;
    om = fail ? 1.0f : om;
    sl = step;
    pr = r;
    bool stop = ((s < thr) SDF_AND (!fail)) SDF_OR (steps >= max_steps);
    float tn = t + step;
    bool past = strict ? !(tn < tmax) : !(tn <= tmax);  // also NaN
    last = fail ? sdf_inf() : s;
    t = stop ? t : tn;
    return stop SDF_OR past;
}

// Cone tracing of a primary ray (aa = "cone"): the cone's radius is the pixel footprint.
// Where the ray passes an edge (d under the radius without hitting), the closest approach
// (smallest d / radius = ca, at t = cb; 2: none) is a partial hit of coverage 1 - ca,
// composited front to back (at most 4 events); the final hit, or the background, takes the
// weight left (trans). A step records at most one event: `emitted`, at t = et with weight ew.
SDF_FN void sdf_cone_emit(float coverage, float at, SDF_INOUT(float) trans, SDF_INOUT(int) events, SDF_OUT(bool) emitted,
                          SDF_OUT(float) et, SDF_OUT(float) ew) {
    emitted = events < 4 && coverage > 0.0f;
    if (emitted) {
        et = at;
        ew = trans * coverage;
        trans *= 1.0f - coverage;
        events += 1;
    }
}
SDF_FN bool sdf_cone_step(float d, float t0, float tmax, int steps, int max_steps, float eps, float foot_base, float foot_slope,
                          SDF_INOUT(float) t, SDF_INOUT(float) ca, SDF_INOUT(float) cb, SDF_INOUT(float) trans,
                          SDF_INOUT(int) events, SDF_OUT(bool) emitted, SDF_OUT(float) et, SDF_OUT(float) ew, SDF_OUT(bool) hit) {
    float path = t0 + t;
    float radius = max(sdf_footprint(foot_base, foot_slope, path), 1e-30f);
    bool done = false;
    hit = false;
    emitted = false;
    et = 0.0f;
    ew = 0.0f;
    if (d < sdf_thr(eps, path)) {
        done = true;  // the axis hits: this surface takes the remaining weight
        hit = true;
    } else if (isnan(d)) {
        done = true;
    } else {
        float rho = d / radius;
        if (rho < 1.0f) {
            if (rho < ca) {
                ca = rho;
                cb = t;
            }
        } else if (ca < 1.0f) {
            sdf_cone_emit(1.0f - ca, cb, trans, events, emitted, et, ew);  // left an edge zone
            ca = 2.0f;
        }
        if (trans < 1e-3f) {
            done = true;  // fully covered by edges
        } else if (steps >= max_steps) {
            done = true;
            hit = d < radius;
        } else {
            t = t + d;
            done = !(t <= tmax);
        }
        if (done && !hit && ca < 1.0f) sdf_cone_emit(1.0f - ca, cb, trans, events, emitted, et, ew);
    }
    return done;
}

// A finished relaxed march hit when its last value is under the threshold, or, out of
// steps, within one pixel footprint.
SDF_FN bool sdf_relaxed_hit(float last, float path, int steps, int max_steps, float eps, float foot_base, float foot_slope) {
    return last < sdf_thr(eps, path) || (steps >= max_steps && last < sdf_footprint(foot_base, foot_slope, path));
}

// Where a camera or bounce ray's hit lands: moved on by its last distance (still outside,
// 1-Lipschitz, and much closer to the surface, wherever the last step began).
SDF_FN float sdf_hit_t(float t, float last, bool hit) { return hit && last > 0.0f ? t + last : t; }

// Raw fields (.vm models, no distance bound): steps of |f| / L (inv_l = 1 / L, a Lipschitz
// estimate the render plan samples), clamped to [one pixel footprint, max_step]. L bounds
// the steepest gradient sampled near the surface, so most steps fall well short (bear.vm's
// median gradient is a sixth of its L); two rules take longer ones, up to
// sdf_raw_secant_reach() times the step (4 times cost test_accel's floating spheres 0.3 dB
// against their distance picture):
//  * a camera ray where the field falls steps just past the zero that the secant of its
//    last two samples predicts: a sign change there costs a refinement or two, where
//    footprint-sized steps and halvings took several (not shadow rays: theirs missed the
//    seams of spheres and floor);
//  * a shadow ray where the field rises (leaving its surface) takes the longer step (bear.vm's
//    shadow rays: 16.3 -> 9.5 evaluations a pixel, the same picture).
// And a camera ray whose secant puts the zero within its step steps just past it instead (a
// bracket under a threshold ends the ray with no refinement: colonnade.vm's hits took 6
// evaluations, the last a refinement after a footprint step far past the zero).
// A sign change (f <= 0) is refined to the outside end of the bracket [prev, hi] (at most 12
// evaluations; the first three by sdf_raw_probe, then halvings). `shadow`: any sign change is
// a hit. `refine` counts the refinements (0 while marching); `prev` is the previous t (-1
// before the first step) and the bracket's outside end, `pv` the value there (NaN: unknown),
// `fhi` the value at `hi`. Thin features (under a step or two, or where the estimate is low)
// can be missed: the price of no bound.
SDF_FN float sdf_raw_secant_reach() { return 2.0f; }

SDF_FN float sdf_raw_probe(float lo, float flo, float hi, float fhi, float thr, float refine) {
    float w = hi - lo;
    float mid = lo + 0.5f * w;
    float c = lo + w * (flo / (flo - fhi));  // where the chord crosses zero
    // Half a threshold past it, toward the end farther from it: when the chord is close, the
    // next probe lands on the other side and the bracket is under a threshold.
    float x = (c - lo > hi - c) ? c - 0.45f * thr : c + 0.45f * thr;
    x = clamp(x, lo + 0.0625f * w, hi - 0.0625f * w);
    bool chord = (refine < 4.0f) SDF_AND (flo > 0.0f) SDF_AND (c >= lo) SDF_AND (c <= hi);  // (NaN: halve)
    return chord ? x : mid;
}

SDF_FN bool sdf_raw_step(float s, float t0, float tmax, bool shadow, int steps, int max_steps, float eps, float foot_base,
                         float foot_slope, float inv_l, float max_step, SDF_INOUT(float) t, SDF_INOUT(float) prev,
                         SDF_INOUT(float) pv, SDF_INOUT(float) hi, SDF_INOUT(float) fhi, SDF_INOUT(float) refine,
                         SDF_OUT(bool) hit) {
    float path = t0 + t;
    float thr = sdf_thr(eps, path);
    bool done = false;
    hit = false;
    if (refine > 0.0f) {
        if (s < 0.0f) {
            hi = t;
            fhi = s;
        } else {
            prev = t;
            pv = s;
        }
        refine += 1.0f;
        if (refine > 12.0f || hi - prev < thr) {
            t = prev;
            done = true;
            hit = true;
        } else {
            t = sdf_raw_probe(prev, pv, hi, fhi, thr, refine);
        }
    } else if (s <= 0.0f) {  // a sign change (values are not distances: "close" means nothing)
        if (s == 0.0f || prev < 0.0f || shadow) {
            done = true;
            hit = true;
        } else if (t - prev < thr) {  // a bracket already as narrow as refinement makes it
            t = prev;
            done = true;
            hit = true;
        } else {
            hi = t;
            fhi = s;
            refine = 1.0f;
            t = sdf_raw_probe(prev, pv, hi, fhi, thr, refine);
        }
    } else {
        float fp = sdf_footprint(foot_base, foot_slope, path);
        float step = fp;
        if (!isnan(s)) {
            float v = s * inv_l;
            step = v < fp ? fp : (max_step < v ? max_step : v);
            float c = s * (t - prev) / (pv - s);  // the secant's zero, from t (pv > s: falling)
            float reach = min(sdf_raw_secant_reach() * max(fp, v), max_step);
            bool ahead = (!shadow) SDF_AND (prev >= 0.0f) SDF_AND (pv > s) SDF_AND (c > step) SDF_AND (step < reach);
            step = ahead ? min(c + 0.5f * thr, reach) : step;
            // The zero predicted within the step: just past it instead, so that a sign change
            // there leaves a bracket under a threshold (a hit with no refinement); not twice in
            // a row (`hi` holds where the last such step went), so that a ray passing close to
            // a surface goes on by the normal step.
            bool close = (!shadow) SDF_AND (prev >= 0.0f) SDF_AND (pv > s) SDF_AND (c >= 0.0f) SDF_AND (c + 0.5f * thr < step) SDF_AND
                         (hi != t);
            step = close ? c + 0.5f * thr : step;
            hi = close ? t + step : hi;
            bool rising = shadow SDF_AND (prev >= 0.0f) SDF_AND (pv < s);
            step = rising ? reach : step;
        }
        prev = t;
        pv = s;
        t = t + step;
        done = !(t <= tmax);
    }
    if (!done && steps >= max_steps) {
        done = true;
        hit = refine > 0.0f;  // inside a bracket: take its outside end
        if (hit) t = prev;
    }
    return done;
}

// Soft shadows: Quilez's penumbra estimate with the closest-approach refinement (for a step
// s longer than the previous positive distance b, the point both spheres touch:
// y = (s^2 + h^2 - b^2) / 2s, which is h^2 / 2b when s = b), marching through occluders in
// steps of a quarter cone width (w: the light's angular width); res is the smallest cone
// fraction (<= -1: fully inside, the march ends). Over-relaxed like sdf_relaxed_step, but
// only far from any penumbra (h >= 4 cone widths) and from surfaces, so the samples that
// decide res are where plain tracing takes them; no sample after a failed relaxed step.
SDF_FN bool sdf_soft_step(float h, float t0, float tmax, float w, int steps, int max_steps, float eps, SDF_INOUT(float) t,
                          SDF_INOUT(float) res, SDF_INOUT(float) prev, SDF_INOUT(float) om, SDF_INOUT(float) pr,
                          SDF_INOUT(float) sl) {
    float thr = sdf_thr(eps, t0 + t);
    bool pos = h > 0.0f;
    float r = abs(h);
    bool fail = (om > 1.0f) SDF_AND (sl > pr) SDF_AND ((r + pr < sl) SDF_OR (!pos));
    float y0 = ((sl > prev) SDF_AND (prev < 1e19f)) ? (sl * sl + h * h - prev * prev) / (2.0f * sl) : h * h / (2.0f * prev);
    float y = min(max(y0, 0.0f), 0.999f * h);
    float dd = sqrt(max(h * h - y * y, 0.0f));
    float est = pos ? dd / (w * max(t - y, 1e-20f)) : h / (w * max(t, 1e-20f));
    res = ((est < res) SDF_AND (!fail)) ? est : res;  // NaN keeps res
    prev = fail ? prev : (pos ? h : 1e20f);
    bool far = pos SDF_AND (h > 4.0f * w * t) SDF_AND (h > 8.0f * thr) SDF_AND (t + om * h < tmax);
    float step = fail ? pr - sl : (pos ? max((far ? om : 1.0f) * h, thr) : max(0.25f * w * t, thr));
    om = fail ? 1.0f : om;
    sl = step;
    pr = r;
    t = t + step;
    return isnan(h) SDF_OR (res <= -1.0f) SDF_OR (steps >= max_steps) SDF_OR (!(t < tmax));
}

// The light that passes a soft shadow march's smallest cone fraction res (smoothstep).
SDF_FN float sdf_penumbra(float res) {
    res = clamp(res, -1.0f, 1.0f);
    return 0.25f * (1.0f + res) * (1.0f + res) * (2.0f - res);
}

// ---- surfaces ----
// Tetrahedron technique: the gradient is sum_k tetra(k) * map(p + e * tetra(k)), with e
// sdf_normal_eps (never under what floats at p resolve).
SDF_FN vec3 sdf_tetra(int k) {
    vec3 v = vec3(1.0f);
    if (k == 0) v = vec3(1.0f, -1.0f, -1.0f);
    if (k == 1) v = vec3(-1.0f, -1.0f, 1.0f);
    if (k == 2) v = vec3(-1.0f, 1.0f, -1.0f);
    return v;
}
SDF_FN float sdf_normal_eps(float eps, vec3 p, float path) { return max(sdf_thr(eps, path), 2e-5f * (1.0f + sdf_maxabs3(p))); }
// The unit normal from the tetrahedron's gradient g; a flat or broken field faces the viewer.
SDF_FN vec3 sdf_normal(vec3 g, vec3 dir) {
    float len2 = dot(g, g);
    return (len2 > 1e-30f && sdf_finite(len2)) ? g * (1.0f / sqrt(len2)) : -dir;
}

// The normal a hit is shaded with, facing the incoming ray d. A ray inside a solid meets
// its surface from within: the outward normal, flipped. From outside, an estimate facing
// away (at a silhouette's edge the tetrahedron blends in a face the ray cannot see) is bent
// edge-on, a little towards the ray, not flipped: flipped it would point into the solid,
// where the occlusion taps and the lights find nothing (black pixels along edges).
SDF_FN vec3 sdf_facing_normal(vec3 n, vec3 d, bool inside) {
    float dn = dot(d, n);
    if (!(dn > 0.0f)) return n;
    if (inside) return -n;
    return normalize(n - d * (dn + 0.05f));
}

// The picture from the radiance a pixel gathered (never NaN, >= 0): times the exposure,
// then mapped (0: none, the encoding clips at 1; 1: Reinhard's c / (1 + c); 2: ACES, in
// Narkowicz's fit), before the sRGB encoding.
SDF_FN float sdf_tonemap1(float c, float exposure, int mode) {
    float x = c * exposure;
    if (mode == 1) return x / (1.0f + x);
    if (mode == 2) return sdf_clamp01((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f));
    return x;
}

// Material channels made safe to shade with (no NaN/inf, sensible ranges): colours,
// specular and emission >= 0, reflectance and transparency in [0, 1], and these two.
SDF_FN float sdf_safe_shininess(float v) { return sdf_finite(v) ? clamp(v, 0.0f, 1e4f) : 32.0f; }
SDF_FN float sdf_safe_ior(float v) { return (sdf_finite(v) && v > 1e-3f) ? v : 1.5f; }

// Schlick's approximation of the Fresnel reflectance.
SDF_FN float sdf_schlick(float cos_theta, float ior) {
    float r0 = (ior - 1.0f) / (ior + 1.0f);
    r0 *= r0;
    float m = 1.0f - sdf_clamp01(cos_theta);
    float m2 = m * m;
    return r0 + (1.0f - r0) * m2 * m2 * m;
}

// pow with the two cases GLSL leaves undefined made as C++ gives them: x^0 = 1, and 0 for x <= 0.
SDF_FN float sdf_pow(float x, float y) { return y == 0.0f ? 1.0f : (x > 0.0f ? pow(x, y) : 0.0f); }

// Blinn-Phong for unit normal n, light direction l, view direction v (towards the eye):
// what one unit of light radiance adds, before shadowing.
SDF_FN vec3 sdf_blinn_phong(vec3 n, vec3 l, vec3 v, vec3 color, float specular, float shininess) {
    float ndl = dot(n, l);
    float ndh = max(dot(n, normalize(l + v)), 0.0f);
    float spec = specular > 0.0f ? specular * sdf_pow(ndh, shininess) : 0.0f;
    return color * ndl + vec3(spec);
}

// A point light's inverse-square falloff over distance dist.
SDF_FN float sdf_falloff(float dist) { return 1.0f / (dist * dist); }

// Ambient occlusion: 5 taps along the normal, each adding how much nearer a surface is than
// the tap's offset, weighted down 0.95 per tap; visibility 1 - 3 * occlusion.
SDF_FN float sdf_ao_offset(int k) { return 0.01f + 0.12f * float(k) / 4.0f; }
SDF_FN void sdf_ao_tap(float d, int k, SDF_INOUT(float) occ, SDF_INOUT(float) sca) {
    float s = sdf_ao_offset(k);
    if (d < s) occ += (s - d) * sca;  // (NaN adds nothing)
    sca *= 0.95f;
}
SDF_FN float sdf_ao_visibility(float occ) { return sdf_clamp01(1.0f - 3.0f * occ); }

// ---- lights ----
// The default rig, for scripts without a light: a key light over the camera's shoulder and a
// dim fill from the other side, both directional (fwd, right, up: the camera's unit frame).
SDF_FN vec3 sdf_key_light_dir(vec3 fwd, vec3 right, vec3 up) { return normalize(fwd + 0.6f * right - 1.2f * up); }
SDF_FN vec3 sdf_fill_light_dir(vec3 fwd, vec3 right, vec3 up) { return normalize(fwd - 0.8f * right - 0.3f * up); }
SDF_FN vec3 sdf_key_light_color() { return vec3(1.0f, 0.97f, 0.92f); }
SDF_FN vec3 sdf_fill_light_color() { return vec3(0.55f, 0.6f, 0.7f); }
SDF_FN float sdf_key_light_intensity() { return 1.0f; }
SDF_FN float sdf_fill_light_intensity() { return 0.35f; }

// ---- rays and the picture ----
// Clips [t_min, t_max] to the box [lo, hi]; an empty interval gets t_min = inf.
SDF_FN void sdf_clip_box(vec3 lo, vec3 hi, vec3 o, vec3 d, SDF_INOUT(float) t_min, SDF_INOUT(float) t_max) {
    for (int a = 0; a < 3; ++a) {
        if (abs(d[a]) < 1e-30f) {
            if (o[a] < lo[a] || o[a] > hi[a]) t_min = sdf_inf();
            continue;
        }
        float inv = 1.0f / d[a];
        float t1 = (lo[a] - o[a]) * inv;
        float t2 = (hi[a] - o[a]) * inv;
        if (t1 > t2) {
            float s = t1;
            t1 = t2;
            t2 = s;
        }
        t_min = max(t_min, t1);
        t_max = min(t_max, t2);
    }
    if (!(t_min <= t_max)) t_min = sdf_inf();
}

// In a scene with floor planes, rays are clipped to the hull [a, b] of their parts inside
// the box of everything else and under each plane n.p <= w (q = (n, w)): this widens [a, b]
// by the part of [t_min, t_max] under plane q (start with a = inf, b = -inf).
SDF_FN void sdf_hull_plane(vec4 q, vec3 o, vec3 d, float t_min, float t_max, SDF_INOUT(float) a, SDF_INOUT(float) b) {
    float s = q.x * o.x + q.y * o.y + q.z * o.z - q.w;  // under the plane where s + v t <= 0
    float v = q.x * d.x + q.y * d.y + q.z * d.z;
    float t0 = t_min, t1 = t_max;
    bool any = true;
    if (v < 0.0f) t0 = max(t0, -s / v);
    else if (v > 0.0f) t1 = min(t1, -s / v);
    else if (!(s <= 0.0f)) any = false;
    if (any && t0 <= t1) {
        a = min(a, t0);
        b = max(b, t1);
    }
}
// ... and by the part inside the box of everything else (empty when lo > hi).
SDF_FN void sdf_hull_box(vec3 lo, vec3 hi, vec3 o, vec3 d, float t_min, float t_max, SDF_INOUT(float) a, SDF_INOUT(float) b) {
    if (lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z) {
        float t0 = t_min, t1 = t_max;
        sdf_clip_box(lo, hi, o, d, t0, t1);
        if (t0 <= t1) {
            a = t0;
            b = t1;
        }
    }
}

// A camera: pinhole (vertical field of view in degrees) or orthographic (ortho_height world
// units tall). Pixel (x, y) covers [x, x+1) x [y, y+1); row 0 is the top. Degenerate inputs
// (target == position, up parallel to the view) get sane fallbacks rather than NaN rays.
struct SdfCamera {
    vec3 eye, fwd, right, up;
    float half_w, half_h;  // perspective: tan-space half extents; ortho: world half extents
    float inv_w, inv_h;
    float foot_base, foot_slope;  // one pixel's footprint radius at t: base + slope * t
    bool ortho;
};
SDF_FN SdfCamera sdf_make_camera(vec3 position, vec3 target, vec3 up_in, float fov_in, bool ortho, float ortho_height,
                                 float width_in, float height_in) {
    SdfCamera c;
    float width = max(width_in, 1.0f);
    float height = max(height_in, 1.0f);
    c.eye = sdf_finite3(position) ? position : vec3(0.0f, 0.0f, 5.0f);
    vec3 f = target - c.eye;
    c.fwd = (sdf_finite3(f) && dot(f, f) > 1e-20f) ? normalize(f) : vec3(0.0f, 0.0f, -1.0f);
    vec3 up = (sdf_finite3(up_in) && dot(up_in, up_in) > 1e-20f) ? normalize(up_in) : vec3(0.0f, 1.0f, 0.0f);
    vec3 r = cross(c.fwd, up);
    if (dot(r, r) < 1e-12f) {
        up = abs(c.fwd.y) < 0.9f ? vec3(0.0f, 1.0f, 0.0f) : vec3(0.0f, 0.0f, 1.0f);
        r = cross(c.fwd, up);
    }
    c.right = normalize(r);
    c.up = cross(c.right, c.fwd);
    float aspect = width / height;
    c.ortho = ortho;
    if (ortho) {
        float h = (sdf_finite(ortho_height) && ortho_height > 0.0f) ? ortho_height : 2.0f;
        c.half_h = 0.5f * h;
        c.half_w = c.half_h * aspect;
        c.foot_base = 0.70710678f * h / height;  // the disc circumscribing one pixel
        c.foot_slope = 0.0f;
    } else {
        float fov = sdf_finite(fov_in) ? clamp(fov_in, 1e-3f, 179.0f) : 45.0f;
        c.half_h = tan(0.5f * radians(fov));
        c.half_w = c.half_h * aspect;
        c.foot_base = 0.0f;
        c.foot_slope = 0.70710678f * 2.0f * c.half_h / height;
    }
    c.inv_w = 1.0f / width;
    c.inv_h = 1.0f / height;
    return c;
}
// The ray through image point (px, py) in pixels.
SDF_FN void sdf_camera_ray(SdfCamera c, float px, float py, SDF_OUT(vec3) o, SDF_OUT(vec3) d) {
    float u = (2.0f * px * c.inv_w - 1.0f) * c.half_w;
    float v = (1.0f - 2.0f * py * c.inv_h) * c.half_h;
    if (c.ortho) {
        o = c.eye + u * c.right + v * c.up;
        d = c.fwd;
    } else {
        o = c.eye;
        d = normalize(c.fwd + u * c.right + v * c.up);
    }
}

// ---- tile pre-marching ----
// Primary rays are traced in square tiles (holding about 256+ samples, so the CPU's lane
// window stays full) whose rays all start where one cone march along the tile's central ray
// ends: every ray of the tile (directions within the corners' cone, origins within the
// corners') stays within r0 + r1 t of the axis point at the same t, so where the axis has
// distance d at t, the ball of radius d around it holds every ray's points up to t + step
// for step = d - (r0 + r1 t) - thr(t + d): no surface there, nor any point where plain
// tracing could have stopped.
SDF_FN int sdf_tile_size(int samples) { return samples <= 2 ? 16 : (samples <= 8 ? 8 : 4); }
SDF_FN void sdf_tile_cone(SdfCamera c, float x0, float y0, float x1, float y1, SDF_OUT(vec3) o, SDF_OUT(vec3) d,
                          SDF_OUT(vec2) r) {
    sdf_camera_ray(c, 0.5f * (x0 + x1), 0.5f * (y0 + y1), o, d);
    float r0 = 0.0f, r1 = 0.0f;
    for (int k = 0; k < 4; ++k) {
        vec3 qo, qd;
        sdf_camera_ray(c, (k & 1) != 0 ? x1 : x0, (k & 2) != 0 ? y1 : y0, qo, qd);
        r0 = max(r0, length(qo - o));
        r1 = max(r1, length(qd - d));
    }
    r = vec2(r0 * 1.01f + 1e-6f, r1 * 1.01f + 1e-6f);  // rounding margin
}
// Where the pre-march begins when rays are clipped to the box [lo, hi] (a bounded scene
// without floor planes): no ray of the tile is in the box before it, for the axis point is
// then farther from the box than the cone's radius. Where the cone meets the box, the axis
// is in the box grown by the largest radius, within [a, b], so the radius is at most
// r0 + r1 b there: the axis's entry into the box grown by that, less a rounding margin, is
// early enough. max_dist when the cone misses the box. (Before, the march began at the
// camera and spent its first steps far from everything, where a big union's guards skip
// least: 3,300 instructions a step on a 10,000-sphere grid.)
SDF_FN float sdf_premarch_begin(vec3 lo, vec3 hi, vec3 o, vec3 d, vec2 r, float max_dist) {
    float g = r.x + r.y * max_dist;
    float a = 0.0f, b = max_dist;
    sdf_clip_box(lo - vec3(g), hi + vec3(g), o, d, a, b);
    if (!(a <= b)) return max_dist;
    g = r.x + r.y * b;
    float a2 = 0.0f, b2 = max_dist;
    sdf_clip_box(lo - vec3(g), hi + vec3(g), o, d, a2, b2);
    if (!(a2 <= b2)) return max_dist;
    return max(a2 - 1e-3f * (1.0f + a2), 0.0f);
}
// One step of the pre-march at t with distance dist; false when it ends (at most 32 steps,
// and never past max_dist).
SDF_FN bool sdf_premarch_step(float dist, vec2 r, float eps, SDF_INOUT(float) t) {
    float step = dist - (r.x + r.y * t) - sdf_thr(eps, t + dist);
    bool more = step > 1e-3f * max(t, 1.0f);  // (NaN: no)
    if (more) t += step;
    return more;
}

// A 2D model's W x H samples over [-1, 1]^2, both ends included (column i of n, row j of n
// from the top); monotonic in the index, so a tile's interval is its corner pixels'.
SDF_FN float sdf_grid_x(int i, int n) { return n > 1 ? -1.0f + 2.0f * float(i) / float(n - 1) : 0.0f; }
SDF_FN float sdf_grid_y(int j, int n) { return n > 1 ? 1.0f - 2.0f * float(j) / float(n - 1) : 0.0f; }

// Linear light to the sRGB encoding (display values in [0, 1]; NaN -> 0).
SDF_FN float sdf_to_srgb(float v) {
    float r = 1.0f;
    if (!(v > 0.0f)) r = 0.0f;
    else if (v < 1.0f) r = v <= 0.0031308f ? 12.92f * v : 1.055f * pow(v, 1.0f / 2.4f) - 0.055f;
    return r;
}

#ifdef __cplusplus
}  // namespace sdfc::rules
#endif
