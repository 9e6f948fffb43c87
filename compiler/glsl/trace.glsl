//! The last part of the renderer: normals, materials, then sdf_trace (all rays of a sample as one
//! state machine around a single map() call) and sdf_render, which the entry points call.

// Tetrahedron technique: the normal is sum_k k * map(p + e * k).
vec3 sdf_tetra(int k) {
    return k == 0 ? vec3(1.0, -1.0, -1.0) : (k == 1 ? vec3(-1.0, -1.0, 1.0) : (k == 2 ? vec3(-1.0, 1.0, -1.0) : vec3(1.0)));
}

// The material at p, sanitised (no NaN/inf, sensible ranges).
Material sdf_surface(vec3 p) {
    Material m = sdf_material(p);
    m.color = vec3(sdf_nonneg(m.color.x), sdf_nonneg(m.color.y), sdf_nonneg(m.color.z));
    m.specular = sdf_nonneg(m.specular);
    m.emission = vec3(sdf_nonneg(m.emission.x), sdf_nonneg(m.emission.y), sdf_nonneg(m.emission.z));
    m.shininess = sdf_finite(m.shininess) ? clamp(m.shininess, 0.0, 1e4) : 32.0;
    m.reflectance = sdf_clamp01(m.reflectance);
    m.transparency = sdf_clamp01(m.transparency);
    m.ior = (sdf_finite(m.ior) && m.ior > 1e-3) ? m.ior : 1.5;
    return m;
}

float sdf_schlick(float cos_theta, float ior) {
    float r0 = (ior - 1.0) / (ior + 1.0);
    r0 *= r0;
    float m = 1.0 - sdf_clamp01(cos_theta);
    float m2 = m * m;
    return r0 + (1.0 - r0) * m2 * m2 * m;
}

float sdf_pow(float x, float y) {
    if (y == 0.0) return 1.0;
    return x > 0.0 ? pow(x, y) : 0.0;
}

// Settings the CPU compiler resolves (compiler/bytecode/compile.cpp): light directions normalised,
// colours of ambient and background made finite and non-negative.
void sdf_init_scene() {
    if (!SDF_DEFAULT_LIGHTS) {
        for (int i = 0; i < SDF_NUM_LIGHTS; ++i)
            if (sdf_lights[i].directional) {
                vec3 d = sdf_lights[i].direction;
                sdf_lights[i].direction = length(d) > 0.0 ? normalize(d) : vec3(0.0, -1.0, 0.0);
            }
    }
    sdf_ambient = vec3(sdf_nonneg(sdf_ambient.x), sdf_nonneg(sdf_ambient.y), sdf_nonneg(sdf_ambient.z));
    sdf_background = vec3(sdf_nonneg(sdf_background.x), sdf_nonneg(sdf_background.y), sdf_nonneg(sdf_background.z));
}

// A ray waiting to be traced (or, with known = true, a hit already found at thit).
struct SdfRay {
    vec3 o, d, w;
    float tmin, tmax, t0, thit;
    bool inside, known;
    int gen;
};
const int SDF_STACK = SDF_MAX_BOUNCES + 6;

// What sdf_trace is doing: the states that evaluate the distance once per loop turn...
const int SDF_ST_MARCH = 0;   // a camera / bounce ray
const int SDF_ST_CONE = 1;    // the cone of a primary ray (aa = "cone")
const int SDF_ST_NORMAL = 2;  // the 4 taps of a hit's normal
const int SDF_ST_AO = 3;      // the 5 ambient-occlusion taps
const int SDF_ST_SHADOW = 4;  // a shadow ray toward light `li`
// ... and those that do not.
const int SDF_ST_POP = 5;     // next ray from the stack
const int SDF_ST_LIGHT = 6;   // set up light `li`
const int SDF_ST_DONE = 7;

// One primary sample of weight w0: the first hit, then mirror/glass bounces depth first from
// an explicit stack (GLSL has no recursion). Everything the CPU does per ray (marching,
// normals, AO, shadow rays) is one state machine around a single map() call, so shader
// compilers inline the scene once instead of once per use (and never unroll it).
vec3 sdf_trace(vec3 O, vec3 D, float w0) {
    vec3 acc = vec3(0.0);
    SdfRay stack[SDF_STACK];
    int sp = 0;
    float tmin = 0.0, tmax = SDF_MAX_DIST;
    sdf_clip_ray(O, D, tmin, tmax);
    SdfRay r = SdfRay(O, D, vec3(w0), tmin, tmax, 0.0, 0.0, false, false, 0);
    int mode = SDF_ST_POP;
    // Marching state (camera, bounce, cone and shadow rays).
    float t = 0.0, om = SDF_RELAX, pr = 0.0, sl = 0.0, prev = -1.0, lo = 0.0, hi = 0.0, bisect = 0.0;
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
                    om = SDF_RELAX, pr = 0.0, sl = 0.0, prev = -1.0, lo = 0.0, hi = 0.0, bisect = 0.0;
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
                e = max(sdf_thr(path), 2e-5 * (1.0 + sdf_maxabs3(P)));
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
                    falloff = 1.0 / (dist * dist);
                }
                float ndl = dot(Nf, L);
                if (skip || !(ndl > 0.0)) {
                    ++li;
                    continue;
                }
                vec3 H = normalize(L - Dr);
                float ndh = max(dot(Nf, H), 0.0);
                float spec = m.specular > 0.0 ? m.specular * sdf_pow(ndh, m.shininess) : 0.0;
                sc = lw * radiance * falloff * (m.color * ndl + spec);
                if (!SDF_SHADOWS) {
                    acc += sc;
                    ++li;
                    continue;
                }
                float bias = sdf_bias(P, path);
                so = P + Nf * bias;
                sdir = L;
                float a0 = bias;  // (as runtime/cpu/tracer.cpp: edges do not shadow themselves)
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
                om = SDF_RELAX, pr = 0.0, sl = 0.0, res = 1.0, prev = SDF_RAW ? -1.0 : 1e20, lo = 0.0, hi = 0.0, bisect = 0.0;
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
                 : mode == SDF_ST_AO ? P + Nf * (0.01 + 0.12 * float(k) / 4.0)
                 : so + t * sdir;
        float dist = map(pos);
        ++steps;

        if (mode == SDF_ST_MARCH) {
            bool hit;
            bool done = SDF_RAW ? sdf_raw_step(r.inside ? -dist : dist, r.t0, r.tmax, false, steps, t, prev, lo, hi, bisect, hit)
                                : sdf_relaxed_step(r.inside ? -dist : dist, r.t0, r.tmax, false, steps, t, om, pr, sl, hit);
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
            float radius = max(sdf_footprint(t), 1e-30);
            bool done = false, hit = false;
            if (dist < sdf_thr(t)) {
                done = hit = true;
            } else if (isnan(dist)) {
                done = true;
            } else {
                float rho = dist / radius;
                if (rho < 1.0) {
                    if (rho < ca) { ca = rho; cb = t; }
                } else if (ca < 1.0) {
                    float cov = 1.0 - ca;
                    if (ev_n < 4 && cov > 0.0) { ev_t[ev_n] = cb; ev_w[ev_n] = trans * cov; trans *= 1.0 - cov; ++ev_n; }
                    ca = 2.0;
                }
                if (trans < 1e-3) {
                    done = true;
                } else if (steps >= SDF_MAX_STEPS) {
                    done = true;
                    hit = dist < radius;
                } else {
                    t += dist;
                    done = !(t <= tmax);
                }
                if (done && !hit && ca < 1.0) {
                    float cov = 1.0 - ca;
                    if (ev_n < 4 && cov > 0.0) { ev_t[ev_n] = cb; ev_w[ev_n] = trans * cov; trans *= 1.0 - cov; ++ev_n; }
                }
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
            float len2 = dot(g, g);
            vec3 N = (len2 > 1e-30 && sdf_finite(len2)) ? g * (1.0 / sqrt(len2)) : -Dr;  // flat or broken: face the viewer
            Nf = dot(Dr, N) > 0.0 ? -N : N;  // facing the incoming ray
            m = sdf_surface(P);
            bool can_spawn = r.gen < SDF_MAX_BOUNCES;
            float bias = sdf_bias(P, path);
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
            float s = 0.01 + 0.12 * float(k) / 4.0;
            if (dist < s) occ += (s - dist) * sca;  // (NaN adds nothing)
            sca *= 0.95;
            if (++k < 5) continue;
            k = 0;
            acc += lw * m.color * sdf_ambient * sdf_clamp01(1.0 - 3.0 * occ);
            mode = SDF_ST_LIGHT;
        } else {  // SDF_ST_SHADOW
            bool hit = false, done;
            if (SDF_RAW) done = sdf_raw_step(dist, path, stmax, true, steps, t, prev, lo, hi, bisect, hit);
            else if (soft) done = sdf_soft_step(dist, path, stmax, sw, steps, t, res, prev, om, pr, sl);
            else done = sdf_relaxed_step(dist, path, stmax, true, steps, t, om, pr, sl, hit);
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

float sdf_to_srgb(float v) {
    if (!(v > 0.0)) return 0.0;
    if (v >= 1.0) return 1.0;
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

// The picture at fragCoord (GL convention: origin at the bottom left) for a res-sized
// viewport at `time`, with an optional interactive orbit (see sdf_orbit).
vec4 sdf_render(vec2 frag_coord, vec2 res, float time, vec4 orbit, vec2 pan) {
    sdf_time = time;
    sdf_zero = int(min(res.x, 0.0));
    sdf_settings();
    sdf_init_scene();
    float x = floor(frag_coord.x), row = floor(res.y) - 1.0 - floor(frag_coord.y);
    if (SDF_2D) {
        // A 2D model: W x H samples over [-1, 1]^2 including both ends, white inside.
        float sx = res.x > 1.0 ? 2.0 / (floor(res.x) - 1.0) : 0.0;
        float sy = res.y > 1.0 ? 2.0 / (floor(res.y) - 1.0) : 0.0;
        float v = map(vec3(-1.0 + sx * x, 1.0 - sy * row, 0.0)) < 0.0 ? 1.0 : 0.0;
        return vec4(vec3(v), 1.0);
    }
    vec3 pos = sdf_cam_position, target = sdf_cam_target;
    if (orbit.w > 0.0) sdf_orbit(pos, target, sdf_cam_up, orbit, pan);
    sdf_setup_camera(pos, target, sdf_cam_up, sdf_cam_fov, sdf_cam_ortho_height, floor(res));
    vec3 acc = vec3(0.0);
    for (int s = sdf_zero; s < SDF_SAMPLES; ++s) {
        vec3 o, d;
        sdf_camera_ray(x + SDF_OFFSETS[s].x, row + SDF_OFFSETS[s].y, o, d);
        acc += sdf_trace(o, d, SDF_SAMPLE_WEIGHT);
    }
    acc = vec3(acc.x >= 0.0 ? min(acc.x, 1e30) : 0.0, acc.y >= 0.0 ? min(acc.y, 1e30) : 0.0, acc.z >= 0.0 ? min(acc.z, 1e30) : 0.0);
    return vec4(sdf_to_srgb(acc.x), sdf_to_srgb(acc.y), sdf_to_srgb(acc.z), 1.0);
}
