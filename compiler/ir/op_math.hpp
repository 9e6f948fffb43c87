// Scalar semantics shared by the constant folder and the VM, written to match GLSL's
// definitions (mod = x - y*floor(x/y), sign(0) = 0), and the GLSL text of the helpers that
// GLSL lacks (kGlslNoise: compiler/ir/noise.glsl, embedded by the build). Keep each C++ helper
// and its GLSL twin in step.
#pragma once
#include <cmath>
#include <cstdint>

#include "compiler/ir/noise.glsl.hpp"
#include "compiler/ir/pow.glsl.hpp"

namespace sdfc::om {

inline constexpr float kSkipped = INFINITY;  // what a skipped guarded region leaves (Op::Guard)
inline float sqrt_(float a) { return std::sqrt(a); }
inline float clamp1(float a) { return a < -1.0f ? -1.0f : (a > 1.0f ? 1.0f : a); }
inline float min_(float a, float b) { return b < a ? b : a; }
inline float max_(float a, float b) { return a < b ? b : a; }
inline float sign(float a) { return a > 0.0f ? 1.0f : (a < 0.0f ? -1.0f : 0.0f); }
inline float mod_(float a, float b) { return a - b * std::floor(a / b); }
// The transcendentals (op_math.cpp): SLEEF's deterministic, FMA-free functions of 1 ulp
// ("cinz"), whose 4-, 8- and 16-lane versions return the same bits as these scalar ones for
// every input (NaN payloads aside), so the batch VM runs them a vector at a time
// (runtime/eval/vmath.inl) and stays bit for bit the scalar reference and the constant
// folder. Special values as C's libm (pow(-8, 3) = -512, pow(x, 0) = 1, log(-1) = NaN).
float exp_(float a);
float log_(float a);
float sin_(float a);
float cos_(float a);
float tan_(float a);
float asin_(float a);
float acos_(float a);
float atan_(float a);
float atan2_(float a, float b);
float pow_(float a, float b);

// Gradient noise (Perlin's improved noise with an integer hash instead of a permutation
// table, so GLSL computes the same bits: noise.glsl, its twin). Range about [-1, 1]; Lipschitz bound kNoiseLipschitz.
inline uint32_t hash3(uint32_t x, uint32_t y, uint32_t z) {
    uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ z * 0xcb1ab31fu;
    h ^= h >> 16; h *= 0x7feb352du; h ^= h >> 15; h *= 0x846ca68bu; h ^= h >> 16;
    return h;
}
inline float grad3(uint32_t h, float x, float y, float z) {
    uint32_t g = h & 15u;
    float u = g < 8u ? x : y;
    float v = g < 4u ? y : ((g == 12u || g == 14u) ? x : z);
    return ((g & 1u) ? -u : u) + ((g & 2u) ? -v : v);
}
inline float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
inline float lerp(float a, float b, float t) { return a + (b - a) * t; }
inline float noise3(float px, float py, float pz) {
    float fx = std::floor(px), fy = std::floor(py), fz = std::floor(pz);
    // The lattice cell as an int, kept in int's range (a huge or NaN coordinate, say from
    // displace(a, 1e30), would make the conversion undefined; in range nothing changes).
    auto cell = [](float f) {
        constexpr float kMax = 2147483520.0f;  // the largest float below 2^31
        return static_cast<uint32_t>(static_cast<int32_t>(f >= -kMax ? (f <= kMax ? f : kMax) : -kMax));
    };
    uint32_t ix = cell(fx), iy = cell(fy), iz = cell(fz);
    float x = px - fx, y = py - fy, z = pz - fz;
    float u = fade(x), v = fade(y), w = fade(z);
    auto g = [&](uint32_t dx, uint32_t dy, uint32_t dz) {
        return grad3(hash3(ix + dx, iy + dy, iz + dz), x - float(dx), y - float(dy), z - float(dz));
    };
    float r = lerp(lerp(lerp(g(0, 0, 0), g(1, 0, 0), u), lerp(g(0, 1, 0), g(1, 1, 0), u), v),
                   lerp(lerp(g(0, 0, 1), g(1, 0, 1), u), lerp(g(0, 1, 1), g(1, 1, 1), u), v), w);
    return r;
}
// Bound on |grad noise3| (measured over dense samples plus margin; see tests/compiler/test_lipschitz.cpp).
inline constexpr float kNoiseLipschitz = 3.0f;

}  // namespace sdfc::om
