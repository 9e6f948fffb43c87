#include "runtime/eval/gradient.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "compiler/ir/op_math.hpp"

namespace sdfc::grad {

// A dual number: value and gradient. Floats convert to constants (zero gradient).
struct D {
    float v, x, y, z;
    D(float c = 0.0f) : v(c), x(0.0f), y(0.0f), z(0.0f) {}
    D(float v_, float x_, float y_, float z_) : v(v_), x(x_), y(y_), z(z_) {}
};
inline D scale(const D& a, float v, float s) { return D(v, a.x * s, a.y * s, a.z * s); }  // f(a) with f'(a) = s
inline D operator-(const D& a) { return D(-a.v, -a.x, -a.y, -a.z); }
inline D operator+(const D& a, const D& b) { return D(a.v + b.v, a.x + b.x, a.y + b.y, a.z + b.z); }
inline D operator-(const D& a, const D& b) { return D(a.v - b.v, a.x - b.x, a.y - b.y, a.z - b.z); }
inline D operator*(const D& a, const D& b) {
    return D(a.v * b.v, a.x * b.v + a.v * b.x, a.y * b.v + a.v * b.y, a.z * b.v + a.v * b.z);
}
inline D operator/(const D& a, const D& b) {
    const float q = a.v / b.v, inv = 1.0f / b.v;
    return D(q, (a.x - q * b.x) * inv, (a.y - q * b.y) * inv, (a.z - q * b.z) * inv);
}
inline bool operator<(const D& a, const D& b) { return a.v < b.v; }
inline bool operator<=(const D& a, const D& b) { return a.v <= b.v; }
inline bool operator>(const D& a, const D& b) { return a.v > b.v; }
inline bool operator==(const D& a, const D& b) { return a.v == b.v; }
inline bool operator!=(const D& a, const D& b) { return a.v != b.v; }

// Dual twins of what opcodes.def's semantics call, under the names they call them by.
namespace std {
inline D fabs(const D& a) { return a.v < 0.0f ? -a : a; }
inline D floor(const D& a) { return D(::std::floor(a.v)); }
inline D ceil(const D& a) { return D(::std::ceil(a.v)); }
}  // namespace std

namespace om {
// At 0 (the length of a zero vector: a box's distance on its faces, inside) the root has no
// derivative; 0 is the VM's value there and 0 the gradient taken, so the other side decides.
inline D sqrt_(const D& a) {
    const float s = ::std::sqrt(a.v);
    return scale(a, s, s > 0.0f ? 0.5f / s : 0.0f);
}
inline constexpr float kSkipped = ::sdfc::om::kSkipped;
inline D clamp1(const D& a) { return a.v < -1.0f ? D(-1.0f) : (a.v > 1.0f ? D(1.0f) : a); }
inline D min_(const D& a, const D& b) { return b.v < a.v ? b : a; }
inline D max_(const D& a, const D& b) { return a.v < b.v ? b : a; }
inline D sign(const D& a) { return D(::sdfc::om::sign(a.v)); }
inline D mod_(const D& a, const D& b) { return a - b * std::floor(a / b); }
// The transcendentals: values from op_math's (the VM's bits), derivatives from them.
inline D sin_(const D& a) { return scale(a, ::sdfc::om::sin_(a.v), ::sdfc::om::cos_(a.v)); }
inline D cos_(const D& a) { return scale(a, ::sdfc::om::cos_(a.v), -::sdfc::om::sin_(a.v)); }
inline D tan_(const D& a) {
    const float c = ::sdfc::om::cos_(a.v);
    return scale(a, ::sdfc::om::tan_(a.v), 1.0f / (c * c));
}
inline D asin_(const D& a) { return scale(a, ::sdfc::om::asin_(a.v), 1.0f / ::std::sqrt(1.0f - a.v * a.v)); }
inline D acos_(const D& a) { return scale(a, ::sdfc::om::acos_(a.v), -1.0f / ::std::sqrt(1.0f - a.v * a.v)); }
inline D atan_(const D& a) { return scale(a, ::sdfc::om::atan_(a.v), 1.0f / (1.0f + a.v * a.v)); }
inline D exp_(const D& a) {
    const float e = ::sdfc::om::exp_(a.v);
    return scale(a, e, e);
}
inline D log_(const D& a) { return scale(a, ::sdfc::om::log_(a.v), 1.0f / a.v); }
inline D atan2_(const D& a, const D& b) {
    const float r = 1.0f / (a.v * a.v + b.v * b.v);
    return D(::sdfc::om::atan2_(a.v, b.v), (b.v * a.x - a.v * b.x) * r, (b.v * a.y - a.v * b.y) * r,
             (b.v * a.z - a.v * b.z) * r);
}
inline D pow_(const D& a, const D& b) {
    const float p = ::sdfc::om::pow_(a.v, b.v);
    const float da = b.v * ::sdfc::om::pow_(a.v, b.v - 1.0f);
    const bool db0 = b.x == 0.0f && b.y == 0.0f && b.z == 0.0f;  // a constant exponent: no log(a)
    const float db = db0 ? 0.0f : p * ::sdfc::om::log_(a.v);
    return D(p, da * a.x + db * b.x, da * a.y + db * b.y, da * a.z + db * b.z);
}
// Noise's gradient by central differences of the float noise (its derivative is smooth).
inline D noise3(const D& a, const D& b, const D& c) {
    constexpr float h = 1e-3f, s = 0.5f / h;
    const float nx = (::sdfc::om::noise3(a.v + h, b.v, c.v) - ::sdfc::om::noise3(a.v - h, b.v, c.v)) * s;
    const float ny = (::sdfc::om::noise3(a.v, b.v + h, c.v) - ::sdfc::om::noise3(a.v, b.v - h, c.v)) * s;
    const float nz = (::sdfc::om::noise3(a.v, b.v, c.v + h) - ::sdfc::om::noise3(a.v, b.v, c.v - h)) * s;
    return D(::sdfc::om::noise3(a.v, b.v, c.v), nx * a.x + ny * b.x + nz * c.x, nx * a.y + ny * b.y + nz * c.y,
             nx * a.z + ny * b.z + nz * c.z);
}
}  // namespace om

// The registers, structure of arrays (value, d/dx, d/dy, d/dz planes of kLanes each), so
// that the lane loops below vectorise like the VM's.
struct Planes {
    float* v;
    float* x;
    float* y;
    float* z;
    D at(int i) const { return D(v[i], x[i], y[i], z[i]); }
    void set(int i, const D& d) const { v[i] = d.v, x[i] = d.x, y[i] = d.y, z[i] = d.z; }
};

// One instruction over n lanes; a register's planes are L floats apart (n rounded up to
// 8: few points keep the registers in few cache lines).
inline void step(const Instr& in, float* base, size_t L, const float* x, const float* y, const float* z, int n, float time) {
    auto reg = [&](uint16_t r) {
        float* p = base + size_t(r) * 4 * L;
        return Planes{p, p + L, p + 2 * L, p + 3 * L};
    };
    const Planes R = reg(in.out), A = reg(in.a), B = reg(in.b), C = reg(in.c);
    switch (in.op) {
        case Op::VarX:
            for (int i = 0; i < n; ++i) R.set(i, D(x[i], 1.0f, 0.0f, 0.0f));
            return;
        case Op::VarY:
            for (int i = 0; i < n; ++i) R.set(i, D(y[i], 0.0f, 1.0f, 0.0f));
            return;
        case Op::VarZ:
            for (int i = 0; i < n; ++i) R.set(i, D(z[i], 0.0f, 0.0f, 1.0f));
            return;
        case Op::Time:
            for (int i = 0; i < n; ++i) R.set(i, D(time));
            return;
        default: break;
    }
    switch (in.op) {
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl)                                             \
    case Op::name:                                                                                     \
        for (int i = 0; i < n; ++i) {                                                                  \
            [[maybe_unused]] const D a = ar >= 1 ? A.at(i) : D(), b = ar >= 2 ? B.at(i) : D(),         \
                                     c = ar >= 3 ? C.at(i) : D();                                      \
            [[maybe_unused]] const float k = in.k;                                                     \
            R.set(i, D(sem));                                                                          \
        }                                                                                              \
        return;
#include "compiler/ir/opcodes.def"
#undef OP
    }
}

}  // namespace sdfc::grad

namespace sdfc {

struct GradientEvaluator::Regs {
    ::std::vector<float> r;  // 4 planes of kLanes per register
};

GradientEvaluator::GradientEvaluator(uint32_t max_regs) : regs_(new Regs) {
    regs_->r.resize(size_t(std::max<uint32_t>(max_regs, 1)) * 4 * kLanes);
}
GradientEvaluator::~GradientEvaluator() = default;

void GradientEvaluator::eval(const TapeView& t, const float* x, const float* y, const float* z, int n, float time, Dual* out) {
    if (n <= 0) return;
    if (size_t(t.num_regs) * 4 * kLanes > regs_->r.size()) regs_->r.resize(size_t(t.num_regs) * 4 * kLanes);
    float* base = regs_->r.data();
    const size_t L = (size_t(n) + 7) & ~size_t(7);
    for (uint32_t i = 0; i < t.len; ++i) grad::step(t.code[i], base, L, x, y, z, n, time);
    const float* r = base + size_t(t.output(0)) * 4 * L;
    for (int i = 0; i < n; ++i) out[i] = Dual{r[i], r[L + i], r[2 * L + i], r[3 * L + i]};
}

}  // namespace sdfc
