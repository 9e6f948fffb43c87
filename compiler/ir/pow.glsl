//! pow and atan2 in GLSL as the CPU computes them (std::pow, std::atan2 in compiler/ir/opcodes.def):
//! GLSL leaves pow of a negative base, pow(0, y <= 0) and atan(0, 0) undefined (llvmpipe gives
//! NaN, 0 and 3pi/4). compiler/glsl/glsl.cpp pastes it into shaders that use Pow, PowI or Atan2.
// (Choices by mix with a bool, not ?: or if: SwiftShader compiles branches slowly. What a mix
// does not pick may be any value, pow's undefined ones included.)
float sdf_powf(float a, float b) {
    // +-0: +-inf for negative b, +-0 for positive; the sign only for odd powers of -0.
    float m = mix(0.0, uintBitsToFloat(0x7f800000u), b < 0.0);
    bool odd = all(bvec2(b == floor(b), mod(b, 2.0) == 1.0));
    float at0 = mix(m, -m, all(bvec2(odd, 1.0 / a < 0.0)));
    // A negative base: NaN, but for whole powers.
    float r = pow(-a, b);
    float below = mix(mix(-r, r, mod(b, 2.0) == 0.0), uintBitsToFloat(0x7fc00000u), b != floor(b));
    float v = mix(mix(below, pow(a, b), a > 0.0), at0, a == 0.0);
    return mix(v, 1.0, b == 0.0);
}

float sdf_atan2(float y, float x) {
    float zeros = mix(y, mix(3.14159265, -3.14159265, 1.0 / y < 0.0), 1.0 / x < 0.0);  // (signed zeros)
    return mix(atan(y, x), zeros, all(bvec2(y == 0.0, x == 0.0)));
}
