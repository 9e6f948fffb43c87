// Shading the hit points of a Worker, all batched: normals, materials, lights with their
// shadow rays, ambient occlusion, and the rays of the next bounce. Design:
//
//  * Normals: tetrahedron technique, n = sum_k k * f(p + e*k) over k in {(1,-1,-1), (-1,-1,1),
//    (-1,1,-1), (1,1,1)}, e = max(epsilon * max(t, 1), 2e-5 * (1 + |p|)).
//  * Shading (Blinn-Phong, not energy normalised):
//        emission + albedo * ambient * ao
//        + sum_lights  colour * intensity * falloff * shadow * (albedo * max(N.L, 0)
//                      + specular * max(N.H, 0)^shininess)              (when N.L > 0)
//    falloff = 1 / distance^2 for point lights, 1 for directional lights. The shadow rays
//    are marched in marcher.cpp (shadow_hard, shadow_soft, march_raw).
//  * Ambient occlusion: 5 taps along the normal at h = 0.01 .. 0.13 (world units),
//    ao = clamp(1 - 3 * sum max(h - d(p + n h), 0) * 0.95^i, 0, 1) (Quilez); it scales the
//    ambient term only.
//  * Reflection/refraction, iterative (a wavefront of ray generations, not recursion, driven
//    by render_tile in tile.cpp), at most max_bounces generations after the primary one. At
//    a surface with weight W: local shading gets W (1 - reflect)(1 - transparency), the
//    mirror ray W * reflect, and the glass part W (1 - reflect) transparency splits by
//    Schlick's Fresnel F into a reflected ray (F) and a refracted one ((1 - F) * colour,
//    i.e. tinted glass). Inside a solid the ray marches on -d; at the exit it refracts out
//    (1 - F) and reflects back in (F), or reflects totally. When no bounce is left the
//    surface is shaded as opaque (and a ray inside glass is dropped). Rays below 1e-3 of a
//    sample's weight are dropped.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")  // as in marcher.cpp
#endif
#include <algorithm>
#include <cmath>

#include "runtime/cpu/worker.hpp"

namespace sdfc::cpu {
namespace {

using namespace rules;

constexpr int kAoTaps = 5;

// A material channel made safe to shade with, by its clamp rule (compiler/scene/materials.def).
float safe_channel(float v, MatClamp c) {
    switch (c) {
        case MatClamp::NonNeg: return sdf_nonneg(v);
        case MatClamp::Unit: return sdf_clamp01(v);
        case MatClamp::Shininess: return sdf_safe_shininess(v);
        case MatClamp::Ior: return sdf_safe_ior(v);
    }
    return v;
}

}  // namespace

void Worker::compute_normals(const RaySet& h) {
    const size_t n = h.size();
    px_.resize(n * 4), py_.resize(n * 4), pz_.resize(n * 4), pd_.resize(n * 4);
    for (size_t i = 0; i < n; ++i) {
        const glm::vec3 p = h.o(i);
        const float e = sdf_normal_eps(f_.eps, p, h.t0[i]);
        for (int k = 0; k < 4; ++k) {
            const glm::vec3 q = p + e * sdf_tetra(k);
            px_[i * 4 + k] = q.x, py_[i * 4 + k] = q.y, pz_[i * 4 + k] = q.z;
        }
    }
    kind_ = RenderStats::kNormals;
    eval_points(px_.data(), py_.data(), pz_.data(), n * 4, pd_.data());
    kind_ = RenderStats::kRays;
    nx_.resize(n), ny_.resize(n), nz_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        glm::vec3 g(0.0f);
        for (int k = 0; k < 4; ++k) g += sdf_tetra(k) * pd_[i * 4 + k];
        const glm::vec3 nrm = sdf_normal(g, h.d(i));
        nx_[i] = nrm.x, ny_[i] = nrm.y, nz_[i] = nrm.z;
    }
}

// Material channels at the hit points, sanitised (no NaN/inf, sensible ranges).
void Worker::compute_materials(const RaySet& h) {
    const size_t n = h.size();
    mat_.resize(n * kMatOut);
    for (size_t i0 = 0; i0 < n; i0 += kBatch) {
        const int m = static_cast<int>(std::min<size_t>(kBatch, n - i0));
        if (shade_) {
            const TapeView tape = f_.shade_tape();
            shade_->eval(tape, h.ox.data() + i0, h.oy.data() + i0, h.oz.data() + i0, m, f_.time);
            stats.shading_points += static_cast<uint64_t>(m);
            stats.shading_instructions += static_cast<uint64_t>(m) * tape.len;
            for (int c = 0; c < kMatOut; ++c) {
                const float* o = shade_->output(tape, static_cast<uint32_t>(c + 1));
                for (int i = 0; i < m; ++i) mat_[(i0 + i) * kMatOut + c] = o[i];
            }
        } else {
            for (int i = 0; i < m; ++i)
                for (int c = 0; c < kMatOut; ++c) mat_[(i0 + i) * kMatOut + c] = kMatChannelInfo[c].def;
        }
    }
    for (size_t i = 0; i < n; ++i) {
        float* q = &mat_[i * kMatOut];
        for (int c = 0; c < kMatOut; ++c) q[c] = safe_channel(q[c], kMatChannelInfo[c].clamp);
    }
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
    const float min_w = f_.min_weight;
    local_.clear(), lw_.clear(), lnx_.clear(), lny_.clear(), lnz_.clear();
    for (size_t i = 0; i < n; ++i) {
        const glm::vec3 P = h.o(i), D = h.d(i), W = h.w(i);
        const glm::vec3 N(nx_[i], ny_[i], nz_[i]);
        const glm::vec3 Nf = sdf_facing_normal(N, D, h.inside[i]);
        const float* m = &mat_[i * kMatOut];
        const float ior = m[kMatIor];
        const float bias = f_.bias(P, h.t0[i]);
        if (h.inside[i]) {
            // Leaving a transparent solid: refract out, reflect back in (Fresnel / TIR).
            if (!can_spawn) continue;
            const glm::vec3 T = glm::refract(D, Nf, ior);
            float F = 1.0f;
            if (glm::dot(T, T) > 0.0f) F = sdf_schlick(-glm::dot(T, Nf), ior);
            const glm::vec3 wr = W * F, wt = W * (1.0f - F);
            if (rules::sdf_max3(wr) >= min_w) push_secondary(next, P + Nf * bias, glm::reflect(D, Nf), h.t0[i], wr, h.prim[i], true);
            if (rules::sdf_max3(wt) >= min_w) push_secondary(next, P - Nf * bias, glm::normalize(T), h.t0[i], wt, h.prim[i], false);
            continue;
        }
        add_shaded(h.prim[i], W * glm::vec3(m[kMatEmitR], m[kMatEmitG], m[kMatEmitB]));
        const float refl = can_spawn ? m[kMatReflect] : 0.0f;
        const float tr = can_spawn ? m[kMatTransparency] : 0.0f;
        const glm::vec3 lw = W * ((1.0f - refl) * (1.0f - tr));
        if (rules::sdf_max3(lw) > 0.0f) {
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
            if (glm::dot(T, T) > 0.0f) F = sdf_schlick(-glm::dot(D, Nf), ior);
            w_refl += base * F;
            const glm::vec3 wt = base * (1.0f - F) * glm::vec3(m[kMatR], m[kMatG], m[kMatB]);
            if (rules::sdf_max3(wt) >= min_w) push_secondary(next, P - Nf * bias, glm::normalize(T), h.t0[i], wt, h.prim[i], true);
        }
        if (rules::sdf_max3(w_refl) >= min_w) push_secondary(next, P + Nf * bias, glm::reflect(D, Nf), h.t0[i], w_refl, h.prim[i], false);
    }

    const size_t nl = local_.size();
    if (nl == 0) return;

    // Ambient (with occlusion).
    const glm::vec3 amb = f_.ambient;
    if (rules::sdf_max3(amb) > 0.0f) {
        ao_.assign(nl, 1.0f);
        if (f_.ao && !f_.raw) {
            px_.resize(nl * kAoTaps), py_.resize(nl * kAoTaps), pz_.resize(nl * kAoTaps), pd_.resize(nl * kAoTaps);
            for (size_t k = 0; k < nl; ++k) {
                const glm::vec3 P = h.o(local_[k]);
                for (int j = 0; j < kAoTaps; ++j) {
                    const float s = sdf_ao_offset(j);
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
                for (int j = 0; j < kAoTaps; ++j) sdf_ao_tap(pd_[k * kAoTaps + j], j, occ, sca);
                ao_[k] = sdf_ao_visibility(occ);
            }
        }
        for (size_t k = 0; k < nl; ++k) {
            const float* m = &mat_[local_[k] * kMatOut];
            const glm::vec3 lw(lw_[k * 3], lw_[k * 3 + 1], lw_[k * 3 + 2]);
            add_shaded(h.prim[local_[k]], lw * glm::vec3(m[kMatR], m[kMatG], m[kMatB]) * amb * ao_[k]);
        }
    }

    // Direct light, one batched shadow pass per light.
    for (size_t li = 0; li < f_.lights.size(); ++li) {
        const ResolvedLight& light = f_.lights[li];
        const glm::vec3 radiance = light.color * light.intensity;
        if (!(rules::sdf_max3(radiance) > 0.0f) || !std::isfinite(rules::sdf_max3(radiance))) continue;
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
                falloff = sdf_falloff(dist);
            }
            const float ndl = glm::dot(N, L);
            if (!(ndl > 0.0f)) continue;
            const float* m = &mat_[i * kMatOut];
            const glm::vec3 lw(lw_[k * 3], lw_[k * 3 + 1], lw_[k * 3 + 2]);
            const glm::vec3 c = lw * radiance * falloff *
                                sdf_blinn_phong(N, L, -h.d(i), glm::vec3(m[kMatR], m[kMatG], m[kMatB]), m[kMatSpecular], m[kMatShininess]);
            if (!f_.shadows) {
                add_shaded(h.prim[i], c);
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
                add_shaded(h.prim[i], c);  // the segment never enters the scene's bounds
                continue;
            }
            shadow_.push(o, L, tmin, tmax, h.t0[i], glm::vec3(0), h.prim[i], false);
            sh_idx_.push_back(i);
            lrad_.insert(lrad_.end(), {c.x, c.y, c.z});
            sw_.push_back(light.directional ? light.radius : light.radius / dist);
        }
        if (shadow_.size() == 0) continue;
        kind_ = RenderStats::kShadows;
        if (f_.raw) {
            cols_ = li < f_.light_columns.size() ? f_.light_columns[li].get() : nullptr;  // (shadow rays run along the light)
            if (!cols_) raw_shadow_cut(shadow_);  // (the columns end the rays where it would)
            march_raw(shadow_, true);
            cols_ = nullptr;
        } else if (light.radius > 0.0f) {
            shadow_soft(shadow_);
        } else {
            shadow_hard(shadow_);
        }
        kind_ = RenderStats::kRays;
        for (size_t s = 0; s < shadow_.size(); ++s)
            if (vis_[s] > 0.0f) add_shaded(shadow_.prim[s], glm::vec3(lrad_[s * 3], lrad_[s * 3 + 1], lrad_[s * 3 + 2]) * vis_[s]);
    }
}

}  // namespace sdfc::cpu
