//! Gradient noise in GLSL, bit for bit om::noise3 of compiler/ir/op_math.hpp (keep the two in
//! step). compiler/glsl/glsl.cpp pastes it into shaders whose scene uses Op::Noise3 (sdf_noise).
uint sdf_hash3(uint x, uint y, uint z) {
    uint h = x * 0x8da6b343u ^ y * 0xd8163841u ^ z * 0xcb1ab31fu;
    h ^= h >> 16; h *= 0x7feb352du; h ^= h >> 15; h *= 0x846ca68bu; h ^= h >> 16;
    return h;
}
// (Choices by mix with a bool, not ?: or if: SwiftShader compiles branches slowly.)
float sdf_grad3(uint h, vec3 p) {
    uint g = h & 15u;
    float u = mix(p.y, p.x, g < 8u);
    float v = mix(mix(p.z, p.x, any(bvec2(g == 12u, g == 14u))), p.y, g < 4u);
    return mix(u, -u, (g & 1u) != 0u) + mix(v, -v, (g & 2u) != 0u);
}
float sdf_noise(vec3 q) {
    vec3 f = floor(q);
    uvec3 i = uvec3(ivec3(clamp(f, vec3(-2147483520.0), vec3(2147483520.0))));  // in int's range, as the C++
    vec3 x = q - f;
    vec3 w = x * x * x * (x * (x * 6.0 - 15.0) + 10.0);
    float g000 = sdf_grad3(sdf_hash3(i.x, i.y, i.z), x);
    float g100 = sdf_grad3(sdf_hash3(i.x + 1u, i.y, i.z), x - vec3(1, 0, 0));
    float g010 = sdf_grad3(sdf_hash3(i.x, i.y + 1u, i.z), x - vec3(0, 1, 0));
    float g110 = sdf_grad3(sdf_hash3(i.x + 1u, i.y + 1u, i.z), x - vec3(1, 1, 0));
    float g001 = sdf_grad3(sdf_hash3(i.x, i.y, i.z + 1u), x - vec3(0, 0, 1));
    float g101 = sdf_grad3(sdf_hash3(i.x + 1u, i.y, i.z + 1u), x - vec3(1, 0, 1));
    float g011 = sdf_grad3(sdf_hash3(i.x, i.y + 1u, i.z + 1u), x - vec3(0, 1, 1));
    float g111 = sdf_grad3(sdf_hash3(i.x + 1u, i.y + 1u, i.z + 1u), x - vec3(1, 1, 1));
    return mix(mix(mix(g000, g100, w.x), mix(g010, g110, w.x), w.y),
               mix(mix(g001, g101, w.x), mix(g011, g111, w.x), w.y), w.z);
}
