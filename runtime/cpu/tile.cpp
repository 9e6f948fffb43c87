// One tile of a Worker: primary rays, generation 0 (march or cone march), the bounce
// generations, and the tile's pixels and AOVs. Design:
//
//  * Primary rays: `samples` per pixel at the frame's offsets (a Hammersley pattern, see
//    frame.cpp), reconstructed with a box filter over the pixel (equal weights). With
//    aa == "cone", one cone per pixel instead (marcher.cpp), and its partial hits are shaded
//    with their coverage.
//  * Bounces: a wavefront of ray generations (shade.cpp spawns them), not recursion.
//  * AOVs: depth = first-hit distance (max_distance for misses; per pixel the minimum over
//    samples), normal = unit world normal of the first hit (sample average, renormalised),
//    steps = average primary-ray step count.
//  * Alpha (RenderOptions::alpha): 1 minus the weight of the primary rays that missed; their
//    background is then left out of the colour (premultiplied), bounces' misses stay in.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")  // as in marcher.cpp
#endif
#include <algorithm>
#include <cmath>

#include "runtime/cpu/worker.hpp"

namespace sdfc::cpu {


void Worker::render_tile(int x0, int y0, int x1, int y1, Image& img, AovPlane* depth, AovPlane* normal, AovPlane* steps, int row0) {
    const int tw = x1 - x0, th = y1 - y0;
    const int S = f_.samples;
    const size_t npix = static_cast<size_t>(tw) * th, nprim = npix * S;
    accum_.assign(npix * 3, 0.0f);
    prim_depth_.assign(nprim, f_.max_dist);
    prim_steps_.assign(nprim, 0.0f);
    prim_n_.assign(f_.want_normal ? nprim * 3 : 0, 0.0f);
    prim_aw_.assign(nprim, -1.0f);
    miss_.assign(f_.alpha ? npix : 0, 0.0f);
    const float w0 = 1.0f / static_cast<float>(S);
    const glm::vec3 bg = f_.background;

    rays_.clear();
    const float start = f_.premarch ? tile_start(x0, y0, x1, y1) : (f_.raw && !f_.cone ? tile_start_raw(x0, y0, x1, y1) : 0.0f);
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
        else {
            cols_ = f_.camera_columns.get();  // (the primary rays are the camera's)
            march(rays_);
            cols_ = nullptr;
        }
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
        } else if (f_.alpha) {
            miss_[r / S] += rest;
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
            const size_t o = static_cast<size_t>(y - row0) * img.width + x;
            const size_t out = o * static_cast<size_t>(img.channels);
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
                for (int c = 0; c < 3; ++c) img.pixels[out + c] = srgb_to_linear(rgb[c]);
            } else {
                for (int c = 0; c < 3; ++c) {
                    const float v = accum_[p * 3 + c];
                    const float r = v >= 0.0f ? std::min(v, 1e30f) : 0.0f;  // never NaN or inf
                    img.pixels[out + c] = f_.exposure == 1.0f && f_.tonemap == 0 ? r : std::min(rules::sdf_tonemap1(r, f_.exposure, f_.tonemap), 1e30f);
                }
            }
            if (f_.alpha) img.pixels[out + 3] = f_.view == RenderView::Steps ? 1.0f : std::clamp(1.0f - miss_[p], 0.0f, 1.0f);
            // A miss is marked: infinitely far (no real hit is at max_distance's value).
            if (depth) depth->data[o] = dmin < f_.max_dist && std::isfinite(dmin) ? dmin : INFINITY;
            if (steps) steps->data[o] = st;
            if (normal) {
                const float len = glm::length(nsum);
                const glm::vec3 nn = (len > 1e-20f && std::isfinite(len)) ? nsum / len : glm::vec3(0.0f);
                for (int c = 0; c < 3; ++c) normal->data[o * 3 + c] = nn[c];
            }
        }
}

}  // namespace sdfc::cpu
