//! The per-ray marching rules (sphere tracing, raw fields, soft shadows), one distance value
//! at a time, twins of runtime/cpu/tracer.cpp's march(), shadow_hard() and shadow_soft().

float sdf_thr(float path) { return SDF_EPSILON * max(path, 1.0); }
float sdf_footprint(float path) { return sdf_foot_base + sdf_foot_slope * path; }
float sdf_bias(vec3 p, float path) { return 4.0 * sdf_thr(path) + 2e-5 * (1.0 + sdf_maxabs3(p)); }

// Clips [t_min, t_max] to the scene's bounding box; an empty interval gets t_min = inf.
void sdf_clip_ray(vec3 o, vec3 d, inout float t_min, inout float t_max) {
    if (!SDF_CLIP) return;
    for (int a = 0; a < 3; ++a) {
        if (abs(d[a]) < 1e-30) {
            if (o[a] < SDF_LO[a] || o[a] > SDF_HI[a]) t_min = sdf_inf();
            continue;
        }
        float inv = 1.0 / d[a];
        float t1 = (SDF_LO[a] - o[a]) * inv, t2 = (SDF_HI[a] - o[a]) * inv;
        if (t1 > t2) { float s = t1; t1 = t2; t2 = s; }
        t_min = max(t_min, t1);
        t_max = min(t_max, t2);
    }
    if (!(t_min <= t_max)) t_min = sdf_inf();
}

// The marching rules, one distance value at a time (the tracer below owns the only map()
// call, see sdf_trace). Each returns true when its march is over.

// Over-relaxed sphere tracing (Keinert et al. 2014: omega = 1.5, back to the previous
// sphere's boundary and omega = 1 when consecutive unbounding spheres stop overlapping or
// the step went through the surface; plain steps within 8 hit thresholds of a surface) on
// the signed value s at t. A hit is s < epsilon * max(path, 1), or, out of steps, s within
// one pixel footprint; a hit moves on by its last s (still outside: 1-Lipschitz).
// `strict`: shadow rays, which end at t >= tmax (camera and bounce rays at t > tmax).
// The same rules as runtime/cpu/tracer.cpp's march() and shadow_hard().
bool sdf_relaxed_step(float s, float t0, float tmax, bool strict, int steps, inout float t, inout float om, inout float pr,
                      inout float sl, out bool hit) {
    float r = abs(s);
    float thr = SDF_EPSILON * max(t0 + t, 1.0);
    bool fail = om > 1.0 && sl > pr && (r + pr < sl || (!strict && s < 0.0));
    float tr = t + om * s;  // a relaxed step past tmax is not taken: only a plain step may end the ray
    float w = (s > 8.0 * thr && (strict ? tr < tmax : tr <= tmax)) ? om : 1.0;
    float step = fail ? pr - sl : w * s;
    om = fail ? 1.0 : om;
    sl = step;
    pr = r;
    bool stop = (s < thr && !fail) || steps >= SDF_MAX_STEPS;
    float tn = t + step;
    bool past = strict ? !(tn < tmax) : !(tn <= tmax);
    float last = fail ? sdf_inf() : s;
    t = stop ? t : tn;
    float path = t0 + t;
    hit = last < sdf_thr(path) || (steps >= SDF_MAX_STEPS && last < sdf_footprint(path));
    if (hit && !strict && last > 0.0) t += last;
    return stop || past;
}

// Raw fields (.vm models, no distance bound): steps of |f| / L (L a Lipschitz estimate made by
// the compiler as the CPU renderer makes it), clamped to [one pixel footprint, SDF_RAW_MAX_STEP];
// a sign change is refined by bisection to the outside end of the bracket [lo, hi]. `shadow`:
// any sign change is a hit.
bool sdf_raw_step(float s, float t0, float tmax, bool shadow, int steps, inout float t, inout float prev, inout float lo,
                  inout float hi, inout float bisect, out bool hit) {
    float path = t0 + t;
    bool done = false;
    hit = false;
    if (bisect > 0.0) {
        if (s < 0.0) hi = t;
        else lo = t;
        bisect += 1.0;
        if (bisect > 12.0 || hi - lo < sdf_thr(path)) {
            t = lo;
            done = hit = true;
        } else {
            t = 0.5 * (lo + hi);
        }
    } else if (s <= 0.0) {
        if (s == 0.0 || prev < 0.0 || shadow) {
            done = hit = true;
        } else {
            lo = prev;
            hi = t;
            bisect = 1.0;
            t = 0.5 * (lo + hi);
        }
    } else {
        float fp = sdf_footprint(path), step = fp;
        if (!isnan(s)) {
            float v = s * SDF_RAW_INV_LIPSCHITZ;
            step = v < fp ? fp : (SDF_RAW_MAX_STEP < v ? SDF_RAW_MAX_STEP : v);
        }
        prev = t;
        t = t + step;
        done = !(t <= tmax);
    }
    if (!done && steps >= SDF_MAX_STEPS) {
        done = true;
        hit = bisect > 0.0;
        if (hit) t = lo;
    }
    return done;
}

// Soft shadows: Quilez's penumbra estimate with the closest-approach refinement (h and the
// previous positive h; y = (s^2 + h^2 - b^2) / 2s after a step s longer than the previous
// h = b), marching through occluders; res is the smallest cone fraction. Over-relaxed like
// sdf_relaxed_step, only where h >= 4 cone widths and 8 hit thresholds (no sample is taken
// after a failed relaxed step). The same rules as runtime/cpu/tracer.cpp's shadow_soft().
bool sdf_soft_step(float h, float t0, float tmax, float w, int steps, inout float t, inout float res, inout float prev,
                   inout float om, inout float pr, inout float sl) {
    float thr = SDF_EPSILON * max(t0 + t, 1.0);
    bool pos = h > 0.0;
    float r = abs(h);
    bool fail = om > 1.0 && sl > pr && (r + pr < sl || !pos);
    float y0 = sl > prev && prev < 1e19 ? (sl * sl + h * h - prev * prev) / (2.0 * sl) : h * h / (2.0 * prev);
    float y = min(max(y0, 0.0), 0.999 * h);
    float dd = sqrt(max(h * h - y * y, 0.0));
    float est = pos ? dd / (w * max(t - y, 1e-20)) : h / (w * max(t, 1e-20));
    res = (est < res && !fail) ? est : res;  // NaN keeps res
    prev = fail ? prev : (pos ? h : 1e20);
    bool far = pos && h > 4.0 * w * t && h > 8.0 * thr && t + om * h < tmax;
    float step = fail ? pr - sl : (pos ? max((far ? om : 1.0) * h, thr) : max(0.25 * w * t, thr));
    om = fail ? 1.0 : om;
    sl = step;
    pr = r;
    t = t + step;
    return isnan(h) || res <= -1.0 || steps >= SDF_MAX_STEPS || !(t < tmax);
}

float sdf_penumbra(float res) {
    res = clamp(res, -1.0, 1.0);
    return 0.25 * (1.0 + res) * (1.0 + res) * (2.0 - res);
}
