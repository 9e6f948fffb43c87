//! pow and atan2 in GLSL as the CPU computes them (std::pow, std::atan2 in compiler/ir/opcodes.def):
//! GLSL leaves pow of a negative base, pow(0, y <= 0) and atan(0, 0) undefined (llvmpipe gives
//! NaN, 0 and 3pi/4). compiler/glsl/glsl.cpp pastes it into shaders that use Pow, PowI or Atan2.
float sdf_powf(float a, float b) {
    if (b == 0.0) return 1.0;
    if (a == 0.0) {  // +-0: +-inf for negative b, +-0 for positive; the sign only for odd powers of -0
        float m = b < 0.0 ? uintBitsToFloat(0x7f800000u) : 0.0;
        return b == floor(b) && mod(b, 2.0) == 1.0 && 1.0 / a < 0.0 ? -m : m;
    }
    if (a > 0.0) return pow(a, b);
    if (b != floor(b)) return uintBitsToFloat(0x7fc00000u);             // a negative base: NaN
    float r = pow(-a, b);
    return mod(b, 2.0) == 0.0 ? r : -r;                                   // ... but for whole powers
}

float sdf_atan2(float y, float x) {
    if (y == 0.0 && x == 0.0) return 1.0 / x < 0.0 ? (1.0 / y < 0.0 ? -3.14159265 : 3.14159265) : y;  // (signed zeros)
    return atan(y, x);
}
