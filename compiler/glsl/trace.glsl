//! The last part of the renderer: normals, materials, then sdf_trace (all rays of a sample as one
//! state machine around a single map() call) and sdf_render, which the entry points call.

// The material at p, made safe to shade with (the rules of compiler/render/rules.h).
Material sdf_surface(vec3 p) {
    Material m = sdf_material(p);
    m.color = sdf_nonneg3(m.color);
    m.specular = sdf_nonneg(m.specular);
    m.emission = sdf_nonneg3(m.emission);
    m.shininess = sdf_safe_shininess(m.shininess);
    m.reflectance = sdf_clamp01(m.reflectance);
    m.transparency = sdf_clamp01(m.transparency);
    m.ior = sdf_safe_ior(m.ior);
    return m;
}

// Settings the CPU resolves in compiler/bytecode/compile.cpp and compiler/render/plan.cpp: light
// directions normalised, colours of ambient and background made finite and non-negative.
void sdf_init_scene() {
    if (!SDF_DEFAULT_LIGHTS) {
        for (int i = 0; i < SDF_NUM_LIGHTS; ++i)
            if (sdf_lights[i].directional) {
                vec3 d = sdf_lights[i].direction;
                sdf_lights[i].direction = length(d) > 0.0 ? normalize(d) : vec3(0.0, -1.0, 0.0);
            }
    }
    sdf_ambient = sdf_nonneg3(sdf_ambient);
    sdf_background = sdf_nonneg3(sdf_background);
}

// A ray waiting to be traced (or, with known = true, a hit already found at thit).
struct SdfRay {
    vec3 o, d, w;
    float tmin, tmax, t0, thit;
    bool inside, known;
    int gen;
};
const int SDF_STACK = SDF_BOUNCE_CAP + 6;

// What sdf_trace is doing: the states that evaluate the distance once per loop turn...
const int SDF_ST_MARCH = 0;   // a camera / bounce ray
const int SDF_ST_CONE = 1;    // the cone of a primary ray (aa = "cone")
const int SDF_ST_NORMAL = 2;  // the 4 taps of a hit's normal
const int SDF_ST_AO = 3;      // the 5 ambient-occlusion taps
const int SDF_ST_SHADOW = 4;  // a shadow ray toward light `li`
const int SDF_ST_PRE = 5;     // the tile's pre-march (sdf_setup_premarch)
// ... and those that do not.
const int SDF_ST_POP = 6;     // next ray from the stack
const int SDF_ST_LIGHT = 7;   // set up light `li`
const int SDF_ST_DONE = 8;

// One primary sample of weight w0: the first hit, then mirror/glass bounces depth first from
// an explicit stack (GLSL has no recursion). Everything the CPU does per ray (marching,
// normals, AO, shadow rays) is one state machine around a single map() call, so shader
// compilers inline the scene once instead of once per use (and never unroll it).
vec3 sdf_trace(vec3 O, vec3 D, float w0) {
    vec3 acc = vec3(0.0);
    SdfRay stack[SDF_STACK];
    int sp = 0;
    float tmin = SDF_CONE || SDF_RAW ? 0.0 : max(sdf_start, 0.0), tmax = SDF_MAX_DIST;
    sdf_clip_ray(O, D, tmin, tmax);
    SdfRay r = SdfRay(O, D, vec3(w0), tmin, tmax, 0.0, 0.0, false, false, 0);
    int mode = SDF_ST_POP;
    // Marching state (camera, bounce, cone and shadow rays).
    float t = 0.0, om = SDF_RELAX, pr = 0.0, sl = 0.0, prev = -1.0, pv = -1.0, hi = 0.0, fhi = 0.0, refine = 0.0;
    int steps = 0;
    // Cone state: the closest approach (a, at b) of the current edge zone, the partial hits.
    float ca = 2.0, cb = 0.0, trans = 1.0;
    float ev_t[4], ev_w[4];
    int ev_n = 0;
    // The surface being shaded.
    vec3 P = vec3(0.0), Dr = D, Nf = vec3(0.0), g = vec3(0.0), lw = vec3(0.0);
    float path = 0.0, e = 0.0, occ = 0.0, sca = 1.0;
    int k = 0;
    Material m = Material(vec3(0.0), 0.0, 0.0, 0.0, 0.0, 1.0, vec3(0.0));
    // The shadow ray of light li.
    int li = 0;
    vec3 so = vec3(0.0), sdir = vec3(0.0), sc = vec3(0.0);
    float stmax = 0.0, sw = 0.0, res = 1.0;
    bool soft = false;
    for (int q = 0; q < 4; ++q) { ev_t[q] = 0.0; ev_w[q] = 0.0; }
    if (SDF_CONE) {
        mode = SDF_ST_CONE;
        t = tmin;
        if (!(t <= tmax)) {  // misses the scene's box
            acc += sdf_background * w0;
            mode = SDF_ST_DONE;
        }
    } else if (SDF_PREMARCH && sdf_start < 0.0) {
        mode = SDF_ST_PRE;  // then this ray, from where the pre-march ends
        t = sdf_pre_t0;
    } else {
        stack[sp++] = r;
    }

    for (int turn = sdf_zero; turn < 16777216; ++turn) {
        // Transitions that need no distance.
        for (int guard = sdf_zero; guard < 4 * SDF_STACK + SDF_NUM_LIGHTS + 8; ++guard) {
            if (mode == SDF_ST_POP) {
                if (sp == 0) {
                    mode = SDF_ST_DONE;
                    break;
                }
                r = stack[--sp];
                if (r.known) {
                    t = r.thit;
                    mode = SDF_ST_NORMAL;
                } else {
                    t = r.tmin;
                    if (!(t <= r.tmax)) {  // misses the scene's box
                        if (!r.inside) acc += sdf_background * r.w;
                        continue;
                    }
                    om = SDF_RELAX, pr = 0.0, sl = 0.0, prev = -1.0, pv = -1.0, hi = 0.0, fhi = 0.0, refine = 0.0;
                    steps = 0;
                    mode = SDF_ST_MARCH;
                    break;
                }
            }
            if (mode == SDF_ST_NORMAL && k == 0) {
                // A hit: set up the normal's taps.
                P = r.o + r.d * t;
                path = r.t0 + t;
                Dr = r.d;
                e = sdf_normal_eps(SDF_EPSILON, P, path);
                g = vec3(0.0);
                break;
            }
            if (mode == SDF_ST_LIGHT) {
                if (li >= SDF_NUM_LIGHTS) {
                    mode = SDF_ST_POP;
                    continue;
                }
                SdfLight light = sdf_lights[li];
                vec3 radiance = light.color * light.intensity;
                float rmax = sdf_max3(radiance);
                vec3 L = -light.direction;
                float dist = SDF_MAX_DIST, falloff = 1.0;
                bool skip = !(rmax > 0.0) || !sdf_finite(rmax);
                if (!skip && light.directional) {
                    skip = !(dot(L, L) > 0.0);
                    if (!skip) L = normalize(L);
                } else if (!skip) {
                    L = light.position - P;
                    dist = length(L);
                    skip = !(dist > 1e-6);
                    L /= dist;
                    falloff = sdf_falloff(dist);
                }
                float ndl = dot(Nf, L);
                if (skip || !(ndl > 0.0)) {
                    ++li;
                    continue;
                }
                sc = lw * radiance * falloff * sdf_blinn_phong(Nf, L, -Dr, m.color, m.specular, m.shininess);
                if (!SDF_SHADOWS) {
                    acc += sc;
                    ++li;
                    continue;
                }
                float bias = sdf_bias(SDF_EPSILON, P, path);
                so = P + Nf * bias;
                sdir = L;
                float a0 = bias;  // (as runtime/cpu/shade.cpp: edges do not shadow themselves)
                stmax = light.directional ? SDF_MAX_DIST : max(dist - bias, 0.0);
                sdf_clip_ray(so, sdir, a0, stmax);
                if (!(a0 <= stmax)) {  // the segment never enters the scene's box
                    acc += sc;
                    ++li;
                    continue;
                }
                t = a0;
                sw = light.directional ? light.radius : light.radius / dist;
                soft = light.radius > 0.0 && !SDF_RAW;
                om = SDF_RELAX, pr = 0.0, sl = 0.0, res = 1.0, prev = SDF_RAW ? -1.0 : 1e20, pv = -1.0, hi = 0.0, fhi = 0.0, refine = 0.0;
                steps = 0;
                mode = SDF_ST_SHADOW;
                break;
            }
            break;
        }
        if (mode == SDF_ST_DONE) break;
        if (mode >= SDF_ST_POP) continue;  // (not reached: the loop above always gets to a state that evaluates)

        // The distance, once per turn.
        vec3 pos = mode == SDF_ST_MARCH ? r.o + t * r.d
                 : mode == SDF_ST_CONE ? O + t * D
                 : mode == SDF_ST_NORMAL ? P + e * sdf_tetra(k)
                 : mode == SDF_ST_AO ? P + Nf * sdf_ao_offset(k)
                 : mode == SDF_ST_PRE ? sdf_pre_o + t * sdf_pre_d
                 : so + t * sdir;
        float dist = map(pos);
        ++steps;

        if (mode == SDF_ST_MARCH) {
            bool hit = false, done;
            float s = r.inside ? -dist : dist;
            if (SDF_RAW) {
                done = sdf_raw_step(s, r.t0, r.tmax, false, steps, SDF_MAX_STEPS, SDF_EPSILON, sdf_cam.foot_base, sdf_cam.foot_slope,
                                    SDF_RAW_INV_LIPSCHITZ, SDF_RAW_MAX_STEP, t, prev, pv, hi, fhi, refine, hit);
            } else {
                float last;
                done = sdf_relaxed_step(s, r.t0, r.tmax, false, steps, SDF_MAX_STEPS, SDF_EPSILON, t, om, pr, sl, last);
                if (done) {
                    hit = sdf_relaxed_hit(last, r.t0 + t, steps, SDF_MAX_STEPS, SDF_EPSILON, sdf_cam.foot_base, sdf_cam.foot_slope);
                    t = sdf_hit_t(t, last, hit);
                }
            }
            if (done) {
                if (hit) {
                    mode = SDF_ST_NORMAL;
                    k = 0;
                } else {
                    if (!r.inside) acc += sdf_background * r.w;
                    mode = SDF_ST_POP;
                }
            }
        } else if (mode == SDF_ST_CONE) {
            // Cone tracing (primary rays only): where the ray passes an edge (d < the pixel
            // footprint without hitting) the closest approach is a partial hit of coverage
            // 1 - d/r; up to 4 are composited front to back, the final hit takes the rest.
            bool emitted, hit;
            float et, ew;
            bool done = sdf_cone_step(dist, 0.0, tmax, steps, SDF_MAX_STEPS, SDF_EPSILON, sdf_cam.foot_base, sdf_cam.foot_slope, t, ca,
                                      cb, trans, ev_n, emitted, et, ew, hit);
            if (emitted) {
                ev_t[ev_n - 1] = et;
                ev_w[ev_n - 1] = ew;
            }
            if (done) {
                for (int q = 0; q < 4; ++q)
                    if (q < ev_n) stack[sp++] = SdfRay(O, D, vec3(ev_w[q] * w0), 0.0, 0.0, 0.0, ev_t[q], false, true, 0);
                float rest = trans * w0;
                if (hit) stack[sp++] = SdfRay(O, D, vec3(rest), 0.0, 0.0, 0.0, t, false, true, 0);
                else acc += sdf_background * rest;
                mode = SDF_ST_POP;
                k = 0;
            }
        } else if (mode == SDF_ST_NORMAL) {
            g += sdf_tetra(k) * dist;
            if (++k < 4) continue;
            k = 0;
            vec3 N = sdf_normal(g, Dr);
            Nf = sdf_facing_normal(N, Dr, r.inside);
            m = sdf_surface(P);
            bool can_spawn = r.gen < SDF_MAX_BOUNCES;
            float bias = sdf_bias(SDF_EPSILON, P, path);
            mode = SDF_ST_POP;
            if (r.inside) {
                // Leaving a transparent solid: refract out, reflect back in (Fresnel / TIR).
                if (!can_spawn) continue;
                vec3 T = refract(Dr, Nf, m.ior);
                float F = 1.0;
                if (dot(T, T) > 0.0) F = sdf_schlick(-dot(T, Nf), m.ior);
                vec3 wr = r.w * F, wt = r.w * (1.0 - F);
                if (sdf_max3(wr) >= SDF_MIN_WEIGHT && sp < SDF_STACK) {
                    vec3 o = P + Nf * bias, d = reflect(Dr, Nf);
                    float a0 = 0.0, b0 = SDF_MAX_DIST;
                    sdf_clip_ray(o, d, a0, b0);
                    stack[sp++] = SdfRay(o, d, wr, a0, b0, path, 0.0, true, false, r.gen + 1);
                }
                if (sdf_max3(wt) >= SDF_MIN_WEIGHT && sp < SDF_STACK) {
                    vec3 o = P - Nf * bias, d = normalize(T);
                    float a0 = 0.0, b0 = SDF_MAX_DIST;
                    sdf_clip_ray(o, d, a0, b0);
                    stack[sp++] = SdfRay(o, d, wt, a0, b0, path, 0.0, false, false, r.gen + 1);
                }
                continue;
            }
            acc += r.w * m.emission;
            float refl = can_spawn ? m.reflectance : 0.0;
            float tr = can_spawn ? m.transparency : 0.0;
            lw = r.w * ((1.0 - refl) * (1.0 - tr));
            if (can_spawn) {
                vec3 w_refl = r.w * refl;
                if (tr > 0.0) {
                    vec3 base = r.w * ((1.0 - refl) * tr);
                    vec3 T = refract(Dr, Nf, 1.0 / m.ior);
                    float F = 1.0;
                    if (dot(T, T) > 0.0) F = sdf_schlick(-dot(Dr, Nf), m.ior);
                    w_refl += base * F;
                    vec3 wt = base * (1.0 - F) * m.color;  // tinted glass
                    if (sdf_max3(wt) >= SDF_MIN_WEIGHT && sp < SDF_STACK) {
                        vec3 o = P - Nf * bias, d = normalize(T);
                        float a0 = 0.0, b0 = SDF_MAX_DIST;
                        sdf_clip_ray(o, d, a0, b0);
                        stack[sp++] = SdfRay(o, d, wt, a0, b0, path, 0.0, true, false, r.gen + 1);
                    }
                }
                if (sdf_max3(w_refl) >= SDF_MIN_WEIGHT && sp < SDF_STACK) {
                    vec3 o = P + Nf * bias, d = reflect(Dr, Nf);
                    float a0 = 0.0, b0 = SDF_MAX_DIST;
                    sdf_clip_ray(o, d, a0, b0);
                    stack[sp++] = SdfRay(o, d, w_refl, a0, b0, path, 0.0, false, false, r.gen + 1);
                }
            }
            if (!(sdf_max3(lw) > 0.0)) continue;
            // Local shading: ambient (with occlusion), then the lights.
            li = 0;
            mode = SDF_ST_LIGHT;
            if (sdf_max3(sdf_ambient) > 0.0) {
                if (SDF_AO) {
                    mode = SDF_ST_AO;
                    occ = 0.0;
                    sca = 1.0;
                } else {
                    acc += lw * m.color * sdf_ambient;
                }
            }
        } else if (mode == SDF_ST_AO) {
            sdf_ao_tap(dist, k, occ, sca);
            if (++k < 5) continue;
            k = 0;
            acc += lw * m.color * sdf_ambient * sdf_ao_visibility(occ);
            mode = SDF_ST_LIGHT;
        } else if (mode == SDF_ST_PRE) {
            bool more = sdf_premarch_step(dist, sdf_pre_r, SDF_EPSILON, t);
            if (!more || steps >= 32 || !(t < SDF_MAX_DIST)) {
                sdf_start = t;
                float a0 = t, b0 = SDF_MAX_DIST;
                sdf_clip_ray(O, D, a0, b0);
                stack[sp++] = SdfRay(O, D, vec3(w0), a0, b0, 0.0, 0.0, false, false, 0);
                mode = SDF_ST_POP;
            }
        } else {  // SDF_ST_SHADOW
            bool hit = false, done;
            if (SDF_RAW) {
                done = sdf_raw_step(dist, path, stmax, true, steps, SDF_MAX_STEPS, SDF_EPSILON, sdf_cam.foot_base, sdf_cam.foot_slope,
                                    SDF_RAW_INV_LIPSCHITZ, SDF_RAW_MAX_STEP, t, prev, pv, hi, fhi, refine, hit);
            } else if (soft) {
                done = sdf_soft_step(dist, path, stmax, sw, steps, SDF_MAX_STEPS, SDF_EPSILON, t, res, prev, om, pr, sl);
            } else {
                float last;
                done = sdf_relaxed_step(dist, path, stmax, true, steps, SDF_MAX_STEPS, SDF_EPSILON, t, om, pr, sl, last);
                if (done) hit = sdf_relaxed_hit(last, path + t, steps, SDF_MAX_STEPS, SDF_EPSILON, sdf_cam.foot_base, sdf_cam.foot_slope);
            }
            if (done) {
                float vis = soft ? sdf_penumbra(res) : (hit ? 0.0 : 1.0);
                if (vis > 0.0) acc += sc * vis;
                ++li;
                mode = SDF_ST_LIGHT;
            }
        }
    }
    return acc;
}

// The frame's settings and camera for a res-sized viewport at `time`, with an optional
// interactive orbit (see sdf_orbit); then the pixel's tile pre-march is due. Returns the
// pixel (column, row from the top).
vec2 sdf_setup(vec2 frag_coord, vec2 res, float time, vec4 orbit, vec2 pan) {
    sdf_time = time;
    sdf_zero = int(min(res.x, 0.0));
    sdf_settings();
    sdf_init_scene();
    float x = floor(frag_coord.x), row = floor(res.y) - 1.0 - floor(frag_coord.y);
    vec3 pos = sdf_cam_position, target = sdf_cam_target;
    if (orbit.w > 0.0) sdf_orbit(pos, target, sdf_cam_up, orbit, pan);
    sdf_cam = sdf_make_camera(pos, target, sdf_cam_up, sdf_cam_fov, SDF_ORTHO, sdf_cam_ortho_height, floor(res.x), floor(res.y));
    if (SDF_PREMARCH) sdf_setup_premarch(x, row, floor(res));
    return vec2(x, row);
}

// A 2D model: W x H samples over [-1, 1]^2 including both ends, white inside.
float sdf_2d_pixel(vec2 px, vec2 res) {
    return map(vec3(sdf_grid_x(int(px.x), int(res.x)), sdf_grid_y(int(px.y), int(res.y)), 0.0)) < 0.0 ? 1.0 : 0.0;
}

// Sample s of the pixel's SDF_SAMPLES: its radiance times its weight (linear, before tone mapping).
vec3 sdf_sample_radiance(vec2 frag_coord, vec2 res, float time, vec4 orbit, vec2 pan, int s) {
    vec2 px = sdf_setup(frag_coord, res, time, orbit, pan);
    if (SDF_2D) return vec3(sdf_2d_pixel(px, floor(res))) * SDF_SAMPLE_WEIGHT;
    vec2 off = sdf_sample_offset(s, SDF_SAMPLES);
    vec3 o, d;
    sdf_camera_ray(sdf_cam, px.x + off.x, px.y + off.y, o, d);
    return sdf_trace(o, d, SDF_SAMPLE_WEIGHT);
}

// A pixel's radiance as display-ready colour: exposure and tone mapping, then sRGB.
vec4 sdf_display(vec3 acc) {
    acc = vec3(acc.x >= 0.0 ? min(acc.x, 1e30) : 0.0, acc.y >= 0.0 ? min(acc.y, 1e30) : 0.0, acc.z >= 0.0 ? min(acc.z, 1e30) : 0.0);
    acc = vec3(sdf_tonemap1(acc.x, SDF_EXPOSURE, SDF_TONEMAP), sdf_tonemap1(acc.y, SDF_EXPOSURE, SDF_TONEMAP), sdf_tonemap1(acc.z, SDF_EXPOSURE, SDF_TONEMAP));
    return vec4(sdf_to_srgb(acc.x), sdf_to_srgb(acc.y), sdf_to_srgb(acc.z), 1.0);
}

// The picture at fragCoord (GL convention: origin at the bottom left), every sample.
vec4 sdf_render(vec2 frag_coord, vec2 res, float time, vec4 orbit, vec2 pan) {
    vec2 px = sdf_setup(frag_coord, res, time, orbit, pan);
    if (SDF_2D) return vec4(vec3(sdf_2d_pixel(px, floor(res))), 1.0);
    vec3 acc = vec3(0.0);
    for (int s = sdf_zero; s < SDF_SAMPLES; ++s) {
        vec2 off = sdf_sample_offset(s, SDF_SAMPLES);
        vec3 o, d;
        sdf_camera_ray(sdf_cam, px.x + off.x, px.y + off.y, o, d);
        acc += sdf_trace(o, d, SDF_SAMPLE_WEIGHT);
    }
    return sdf_display(acc);
}
