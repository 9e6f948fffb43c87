// Interval semantics of every opcode, the batch interval evaluator and tape simplification.
//
// Exactness. The VM's arithmetic is IEEE single precision with round-to-nearest, which is
// monotonic: x <= y implies fl(x) <= fl(y). So for an op that is monotonic in each operand
// and rounds once (add, sub, mul, min, max, sqrt, square, ...), computing the interval's
// ends with the same float operation as the VM gives bounds that enclose the VM's results
// exactly, with no outward rounding. Ops whose VM form may round more than once, or may be
// contracted into an FMA by the compiler (MulAddI, Mix, Length2/3, Mod), and libm functions
// (which may differ by an ulp between the scalar and a vectorised libm) are widened by a
// few ulps. Min/max choices compare the interval ends with the same comparisons the VM's
// om::min_ / om::max_ make, so a decided choice is the VM's choice at every point.
#include "runtime/eval/interval.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <iterator>
#include <new>

// A new opcode must get its interval semantics here: a missing case is an error.
#pragma GCC diagnostic error "-Wswitch"

namespace sdfc {
namespace {

#if defined(__GNUC__)
#define SDFC_IV_INLINE __attribute__((always_inline)) inline
#else
#define SDFC_IV_INLINE inline
#endif

#if defined(__clang__)
#define SDFC_IVDEP _Pragma("clang loop vectorize(assume_safety)")
#elif defined(__GNUC__)
#define SDFC_IVDEP _Pragma("GCC ivdep")
#else
#define SDFC_IVDEP
#endif

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kPi = 3.14159265358979f;

// Outward widening by at least one ulp (two for normal numbers): dn(x) <= the float below x.
// Infinities stay (the margin is capped), NaN stays NaN.
constexpr float kMaxF = std::numeric_limits<float>::max();
SDFC_IV_INLINE float margin(float x, float rel, float abs) {
    const float m = std::fabs(x) * rel + abs;
    return m < kMaxF ? m : kMaxF;  // NaN compares false: NaN stays
}
SDFC_IV_INLINE float dn(float x) { return x - margin(x, 0x1p-22f, 0x1p-126f); }
SDFC_IV_INLINE float up(float x) { return x + margin(x, 0x1p-22f, 0x1p-126f); }
// Wider, for libm results (a few ulps between implementations).
SDFC_IV_INLINE float dnw(float x) { return x - margin(x, 0x1p-18f, 0x1p-120f); }
SDFC_IV_INLINE float upw(float x) { return x + margin(x, 0x1p-18f, 0x1p-120f); }

SDFC_IV_INLINE float mn(float a, float b) { return b < a ? b : a; }
SDFC_IV_INLINE float mx(float a, float b) { return a < b ? b : a; }

// 0 for a finite value, NaN for an infinite or NaN one: added to both ends of a result, it
// turns the result unknown when an operand may be infinite or NaN.
SDFC_IV_INLINE float poison(float lo, float hi) { return (lo - lo) + (hi - hi); }

// Interval product (corners); no NaN for finite operands.
SDFC_IV_INLINE void mul_iv(float al, float ah, float bl, float bh, float& lo, float& hi) {
    float p0 = al * bl, p1 = al * bh, p2 = ah * bl, p3 = ah * bh;
    lo = mn(mn(p0, p1), mn(p2, p3));
    hi = mx(mx(p0, p1), mx(p2, p3));
}

// Monotonic libm function, increasing.
template <class F>
SDFC_IV_INLINE void mono_inc(F f, float al, float ah, float& lo, float& hi) {
    lo = dnw(f(al));
    hi = upw(f(ah));
}

// sin over [l, h] (finite): the endpoints, plus +-1 when a peak may lie inside. `phase`
// shifts the peaks: sin peaks at pi/2 + 2 pi n; cos = sin(x + pi/2) peaks at 2 pi n.
SDFC_IV_INLINE void sin_iv(float l, float h, float peak_at, float (*f)(float), float& lo, float& hi) {
    if (!(h - l < 6.0f) || std::fabs(l) > 1e5f || std::fabs(h) > 1e5f) {
        lo = -1.0f;
        hi = 1.0f;
        return;
    }
    float fl = f(l), fh = f(h);
    lo = dnw(mn(fl, fh));
    hi = upw(mx(fl, fh));
    // Peaks (value +1) at peak_at + 2 pi n, troughs at peak_at + pi + 2 pi n. Widen the
    // search so that a peak just outside by rounding still counts.
    const double tl = double(l) - 1e-3 - double(peak_at), th = double(h) + 1e-3 - double(peak_at);
    const double two_pi = 6.283185307179586;
    if (std::floor(th / two_pi) >= std::ceil(tl / two_pi)) hi = 1.0f;
    if (std::floor((th - 3.141592653589793) / two_pi) >= std::ceil((tl - 3.141592653589793) / two_pi)) lo = -1.0f;
    lo = mx(lo, -1.0f);
    hi = mn(hi, 1.0f);
}

float sinf_(float x) { return std::sin(x); }
float cosf_(float x) { return std::cos(x); }

// Unknown intervals. Invariant: if a point of the box may give NaN, or the interval is
// unknown, both ends are NaN; NaN ends never decide a choice (comparisons are false). An
// op keeps it by adding z (0, or NaN) to both ends, z from one of:
//   Inputs  NaN when an operand has a NaN or infinite end (x * 0 is NaN for inf and NaN;
//           a finite sum that overflows only makes the result unknown needlessly)
//   Result  NaN when the result has a NaN or infinite end: enough for ops whose formulas
//           carry a NaN or infinite operand end into the result (add, sub)
//   B       NaN when operand b has one: min/max carry a's NaN ends (mn(NaN, x) is NaN)
//           but not b's, and infinities are fine for them
//   None    ops that carry NaN ends and make no NaN from finite or infinite operands
//           (plus explicit domain checks: the root of a negative number, ...)
enum class Poison { Inputs, Result, B, None };
template <Op O>
constexpr Poison poison_kind() {
    switch (O) {
        case Op::Add: case Op::Sub: case Op::AddI: case Op::SubI: return Poison::Result;
        case Op::Min: case Op::Max: return Poison::B;
        case Op::Const: case Op::VarX: case Op::VarY: case Op::VarZ: case Op::Time: case Op::Copy: case Op::Neg:
        case Op::MinI: case Op::MaxI: case Op::Sqrt: return Poison::None;
        default: return Poison::Inputs;
    }
}

// The interval semantics of op O: [al, ah] etc. in, [lo, hi] and the choice out.
template <Op O>
SDFC_IV_INLINE void iv(float al, float ah, float bl, float bh, float cl, float ch, float k, float& lo, float& hi,
                       uint8_t& choice) {
    choice = kChoiceBoth;
    constexpr int arity = kOpInfo[int(O)].arity;
    constexpr Poison P = poison_kind<O>();
    float z = 0.0f;
    if constexpr (P == Poison::Inputs) {
        z = arity >= 1 ? al + ah : 0.0f;
        if constexpr (arity >= 2) z += bl + bh;
        if constexpr (arity >= 3) z += cl + ch;
        z *= 0.0f;
    } else if constexpr (P == Poison::B) {
        z = (bl + bh) * 0.0f;
    }
    switch (O) {
        case Op::Const: lo = hi = k; return;
        case Op::VarX:
        case Op::VarY:
        case Op::VarZ:
        case Op::Time:
        case Op::Copy: lo = al; hi = ah; return;  // inputs are set by the evaluator
        case Op::Neg: lo = -ah; hi = -al; return;
        case Op::Abs:
            lo = al >= 0.0f ? al : (ah <= 0.0f ? -ah : 0.0f);
            hi = al >= 0.0f ? ah : (ah <= 0.0f ? -al : mx(-al, ah));
            break;
        case Op::Square: {
            float l2 = al * al, h2 = ah * ah;
            lo = al >= 0.0f ? l2 : (ah <= 0.0f ? h2 : 0.0f);
            hi = al >= 0.0f ? h2 : (ah <= 0.0f ? l2 : mx(l2, h2));
            break;
        }
        case Op::Sqrt:
            lo = std::sqrt(mx(al, 0.0f));
            hi = std::sqrt(mx(ah, 0.0f));
            z += al < 0.0f ? kNaN : 0.0f;  // some point may take the root of a negative number
            break;
        case Op::Sin: sin_iv(al, ah, kPi / 2, sinf_, lo, hi); break;
        case Op::Cos: sin_iv(al, ah, 0.0f, cosf_, lo, hi); break;
        case Op::Tan: {
            // Monotonic between asymptotes at pi/2 + pi n.
            const double pi = 3.141592653589793;
            bool ok = ah - al < 3.0f && std::fabs(al) < 1e5f && std::fabs(ah) < 1e5f &&
                      std::floor((double(ah) + 1e-3 - pi / 2) / pi) < std::ceil((double(al) - 1e-3 - pi / 2) / pi);
            lo = ok ? dnw(std::tan(al)) : -kInf;
            hi = ok ? upw(std::tan(ah)) : kInf;
            break;
        }
        case Op::Asin:
            mono_inc([](float v) { return std::asin(om::clamp1(v)); }, al, ah, lo, hi);
            break;
        case Op::Acos:
            lo = dnw(std::acos(om::clamp1(ah)));
            hi = upw(std::acos(om::clamp1(al)));
            break;
        case Op::Atan: mono_inc([](float v) { return std::atan(v); }, al, ah, lo, hi); break;
        case Op::Exp:
            mono_inc([](float v) { return std::exp(v); }, al, ah, lo, hi);
            lo = mx(lo, 0.0f);
            break;
        case Op::Log:
            mono_inc([](float v) { return std::log(v); }, mx(al, 0.0f), mx(ah, 0.0f), lo, hi);
            z = al < 0.0f ? kNaN : z;
            break;
        case Op::Floor: lo = std::floor(al); hi = std::floor(ah); break;
        case Op::Ceil: lo = std::ceil(al); hi = std::ceil(ah); break;
        case Op::Fract: {
            float f = std::floor(al);
            bool one_cell = f == std::floor(ah);
            lo = one_cell ? al - f : 0.0f;
            hi = one_cell ? ah - f : 1.0f;
            break;
        }
        case Op::Sign: lo = om::sign(al); hi = om::sign(ah); break;
        case Op::Not:
            lo = ((al > 0.0f) | (ah < 0.0f)) ? 0.0f : (((al == 0.0f) & (ah == 0.0f)) ? 1.0f : 0.0f);
            hi = ((al > 0.0f) | (ah < 0.0f)) ? 0.0f : 1.0f;
            break;
        case Op::Add: lo = al + bl; hi = ah + bh; break;
        case Op::Sub: lo = al - bh; hi = ah - bl; break;
        case Op::Mul: mul_iv(al, ah, bl, bh, lo, hi); break;
        case Op::Div: {
            float q0 = al / bl, q1 = al / bh, q2 = ah / bl, q3 = ah / bh;
            lo = mn(mn(q0, q1), mn(q2, q3));
            hi = mx(mx(q0, q1), mx(q2, q3));
            z += ((bl > 0.0f) | (bh < 0.0f)) ? 0.0f : kNaN;  // the divisor may be zero
            break;
        }
        case Op::Min:
            // om::min_(a, b) = b < a ? b : a
            lo = mn(al, bl);
            hi = mn(ah, bh);
            choice = uint8_t((ah <= bl) * kChoiceA + (bh < al) * kChoiceB);  // exclusive
            break;
        case Op::Max:
            // om::max_(a, b) = a < b ? b : a
            lo = mx(al, bl);
            hi = mx(ah, bh);
            choice = uint8_t((ah < bl) * kChoiceB + (bh <= al) * kChoiceA);
            break;
        case Op::Mod: {
            // a - b floor(a / b) lies in [0, b) (b > 0) or (b, 0] (b < 0), up to rounding
            // errors of about an ulp of a.
            float m = mx(std::fabs(al), std::fabs(ah)) * 0x1p-20f + mx(std::fabs(bl), std::fabs(bh)) * 0x1p-20f + 0x1p-120f;
            lo = bl > 0.0f ? -m : bl - m;
            hi = bl > 0.0f ? bh + m : m;
            // The quotient must not overflow (a - b*inf is infinite).
            if (!((bl > 0.0f) | (bh < 0.0f)) || !(mx(std::fabs(al), std::fabs(ah)) < 1e30f * mn(std::fabs(bl), std::fabs(bh))))
                z = kNaN;
            break;
        }
        case Op::Pow: {
            // For a > 0, pow is monotonic in each operand: the extremes are at corners.
            float p0 = std::pow(al, bl), p1 = std::pow(al, bh), p2 = std::pow(ah, bl), p3 = std::pow(ah, bh);
            lo = dnw(mn(mn(p0, p1), mn(p2, p3)));
            hi = upw(mx(mx(p0, p1), mx(p2, p3)));
            z = al > 0.0f ? z : kNaN;
            break;
        }
        case Op::Atan2: lo = -3.1415930f; hi = 3.1415930f; break;
        case Op::Lt:
            lo = al >= bh ? 0.0f : (ah < bl ? 1.0f : 0.0f);
            hi = al >= bh ? 0.0f : 1.0f;
            break;
        case Op::Le:
            lo = al > bh ? 0.0f : (ah <= bl ? 1.0f : 0.0f);
            hi = al > bh ? 0.0f : 1.0f;
            break;
        case Op::Eq: {
            bool disjoint = (ah < bl) | (bh < al);
            bool same = (al == ah) & (bl == bh) & (al == bl);
            lo = same ? 1.0f : 0.0f;
            hi = disjoint ? 0.0f : 1.0f;
            break;
        }
        case Op::Ne: {
            bool disjoint = (ah < bl) | (bh < al);
            bool same = (al == ah) & (bl == bh) & (al == bl);
            lo = disjoint ? 1.0f : 0.0f;
            hi = same ? 0.0f : 1.0f;
            break;
        }
        case Op::And:
        case Op::Or: {
            // Truth of an operand: known true when its interval excludes 0, known false when
            // it is [0, 0].
            bool at = (al > 0.0f) | (ah < 0.0f), af = (al == 0.0f) & (ah == 0.0f);
            bool bt = (bl > 0.0f) | (bh < 0.0f), bf = (bl == 0.0f) & (bh == 0.0f);
            bool t = O == Op::And ? (at & bt) : (at | bt);
            bool f = O == Op::And ? (af | bf) : (af & bf);
            lo = t ? 1.0f : 0.0f;
            hi = f ? 0.0f : 1.0f;
            break;
        }
        case Op::Length2: {
            float a0 = al >= 0.0f ? al : (ah <= 0.0f ? -ah : 0.0f), a1 = mx(-al, ah);
            float b0 = bl >= 0.0f ? bl : (bh <= 0.0f ? -bh : 0.0f), b1 = mx(-bl, bh);
            lo = dn(std::sqrt(a0 * a0 + b0 * b0));
            hi = up(std::sqrt(a1 * a1 + b1 * b1));
            lo = mx(lo, 0.0f);
            break;
        }
        case Op::Length3: {
            float a0 = al >= 0.0f ? al : (ah <= 0.0f ? -ah : 0.0f), a1 = mx(-al, ah);
            float b0 = bl >= 0.0f ? bl : (bh <= 0.0f ? -bh : 0.0f), b1 = mx(-bl, bh);
            float c0 = cl >= 0.0f ? cl : (ch <= 0.0f ? -ch : 0.0f), c1 = mx(-cl, ch);
            lo = dn(std::sqrt(a0 * a0 + b0 * b0 + c0 * c0));
            hi = up(std::sqrt(a1 * a1 + b1 * b1 + c1 * c1));
            lo = mx(lo, 0.0f);
            break;
        }
        case Op::AddI: lo = al + k; hi = ah + k; break;
        case Op::SubI: lo = k - ah; hi = k - al; break;
        case Op::MulI: {
            float p = al * k, q = ah * k;
            lo = mn(p, q);
            hi = mx(p, q);
            z += k - k;
            break;
        }
        case Op::DivI: {
            float p = k / al, q = k / ah;
            lo = mn(p, q);
            hi = mx(p, q);
            z += ((al > 0.0f) | (ah < 0.0f)) ? 0.0f : kNaN;
            z += k - k;
            break;
        }
        case Op::MinI:
            // om::min_(a, k) = k < a ? k : a
            lo = mn(al, k);
            hi = mn(ah, k);
            choice = uint8_t((ah <= k) * kChoiceA + (k < al) * kChoiceB);
            break;
        case Op::MaxI:
            // om::max_(a, k) = a < k ? k : a
            lo = mx(al, k);
            hi = mx(ah, k);
            choice = uint8_t((ah < k) * kChoiceB + (k <= al) * kChoiceA);
            break;
        case Op::ModI: {
            float m = mx(std::fabs(al), std::fabs(ah)) * 0x1p-20f + std::fabs(k) * 0x1p-20f + 0x1p-120f;
            // Within one period, a - k floor(a / k) is a - k f for one integer f: monotonic.
            float fl = std::floor(al / k), fh = std::floor(ah / k);
            bool one = (k > 0.0f) & (fl == fh);
            float base = k * fl;
            lo = one ? al - base - m : (k > 0.0f ? -m : k - m);
            hi = one ? ah - base + m : (k > 0.0f ? k + m : m);
            if (!(mx(std::fabs(al), std::fabs(ah)) < 1e30f * std::fabs(k))) z = kNaN;  // also k == 0
            z += k - k;
            break;
        }
        case Op::PowI: {
            // Integer exponents: even like a square, odd monotonic; other exponents need a >= 0.
            float pl = std::pow(al, k), ph = std::pow(ah, k);
            bool integer = k == std::floor(k) && std::fabs(k) < 16777216.0f;
            bool even = integer && std::fmod(k, 2.0f) == 0.0f;
            bool spans0 = (al < 0.0f) & (ah > 0.0f);
            if (k == 0.0f) {
                lo = hi = 1.0f;
            } else if (even && k > 0.0f) {
                lo = al >= 0.0f ? pl : (ah <= 0.0f ? ph : 0.0f);
                hi = al >= 0.0f ? ph : (ah <= 0.0f ? pl : mx(pl, ph));
            } else {
                lo = mn(pl, ph);
                hi = mx(pl, ph);
                bool monotonic = (integer && !(k < 0.0f && (spans0 || al == 0.0f || ah == 0.0f))) || al > 0.0f;
                if (!monotonic) z = kNaN;
            }
            lo = dnw(lo);
            hi = upw(hi);
            z += k - k;
            break;
        }
        case Op::MulAddI: {
            float p = al * k, q = ah * k;
            lo = dn(mn(p, q)) + bl;  // the VM may round a*k or fuse it into an FMA
            hi = up(mx(p, q)) + bh;
            z += k - k + poison(p, q);  // a*k may overflow, and inf - inf is NaN
            break;
        }
        case Op::Select: {
            // a != 0 ? b : c; a NaN counts as true, like in the VM. Only the side taken
            // needs to be known.
            const bool t = (al > 0.0f) | (ah < 0.0f), f = (al == 0.0f) & (ah == 0.0f);
            const float zb = poison(bl, bh), zc = poison(cl, ch);
            z = (t ? zb : 0.0f) + (f ? zc : 0.0f) + ((t | f) ? 0.0f : zb + zc);
            lo = t ? bl : (f ? cl : mn(bl, cl));
            hi = t ? bh : (f ? ch : mx(bh, ch));
            choice = uint8_t(t * kChoiceB + f * kChoiceC);
            break;
        }
        case Op::Mix: {
            // b + (c - b) * a
            float dl = cl - bh, dh = ch - bl, el, eh;
            mul_iv(dl, dh, al, ah, el, eh);
            z += poison(dl, dh);  // c - b may overflow, and inf * 0 is NaN
            lo = dn(el) + bl;
            hi = up(eh) + bh;
            break;
        }
        case Op::Noise3: lo = -2.001f; hi = 2.001f; break;
    }
    if constexpr (P == Poison::Result) z += (lo + hi) * 0.0f;
    lo += z;
    hi += z;
}

void free_aligned(float* p) { std::free(p); }
float* alloc_floats(size_t count) {  // uninitialised: a register is written before it is read
    size_t bytes = (std::max<size_t>(count, 1) * sizeof(float) + 63) / 64 * 64;
    void* p = std::aligned_alloc(64, bytes);
    if (!p) throw std::bad_alloc();
    return static_cast<float*>(p);
}

template <Op O>
constexpr bool choice_op() {
    return O == Op::Min || O == Op::Max || O == Op::MinI || O == Op::MaxI || O == Op::Select;
}

}  // namespace

namespace {
constexpr uint64_t kChoiceMask = 0
#define OP(name, mn, ar, imm, sem, glsl) | (choice_op<Op::name>() ? uint64_t(1) << int(Op::name) : 0)
#include "compiler/ir/opcodes.def"
#undef OP
    ;
static_assert(kOpCount <= 64);
}  // namespace

bool is_choice_op(Op op) { return (kChoiceMask >> int(op)) & 1; }

Interval eval_interval(Op op, Interval a, Interval b, Interval c, float k, uint8_t* choice) {
    Interval r{};
    uint8_t ch = kChoiceBoth;
    switch (op) {
#define OP(name, mn, ar, imm, sem, glsl) \
    case Op::name: iv<Op::name>(a.lo, a.hi, b.lo, b.hi, c.lo, c.hi, k, r.lo, r.hi, ch); break;
#include "compiler/ir/opcodes.def"
#undef OP
    }
    if (choice) *choice = ch;
    return r;
}

Tape Tape::from(const Program& p, int output) {
    Tape t;
    t.code = p.code;
    t.out = p.outputs.at(static_cast<size_t>(output));
    t.recount();
    t.num_regs = std::max(t.num_regs, p.num_regs);
    t.link();
    return t;
}

void Tape::recount() {
    uint32_t regs = uint32_t(out) + 1, ch = 0;
    for (const Instr& in : code) {
        regs = std::max<uint32_t>(regs, uint32_t(in.out) + 1);
        ch += is_choice_op(in.op);
    }
    num_regs = regs;
    choices = ch;
}

void Tape::link() {
    const size_t n = code.size();
    links.resize(n);
    thread_local std::vector<uint32_t> last;
    last.assign(std::max<uint32_t>(num_regs, uint32_t(out) + 1), kNone);
    const size_t nregs = last.size();
    bool regs_ok = true;
    if (!well_formed)
        for (const Instr& in : code) regs_ok &= (in.out < nregs) & (in.a < nregs) & (in.b < nregs) & (in.c < nregs);
    if (!regs_ok) {
        linked = false;
        return;
    }
    uint32_t sl = 0;
    for (size_t i = 0; i < n; ++i) {
        const Instr& in = code[i];
        Link& l = links[i];
        // Unused operand fields hold some register number: their "def" is never read.
        l.def[0] = last[in.a];
        l.def[1] = last[in.b];
        l.def[2] = last[in.c];
        const uint32_t ch = uint32_t((kChoiceMask >> int(in.op)) & 1);
        l.slot = ch ? sl : kNone;
        sl += ch;
        last[in.out] = uint32_t(i);
    }
    choices = sl;
    out_def = last[out];
    linked = true;
    if (!well_formed) {
        // A tape reading unwritten registers cannot be followed by def links.
        for (size_t i = 0; i < n && linked; ++i)
            for (int j = 0; j < kOpInfo[int(code[i].op)].arity; ++j) linked &= links[i].def[j] != kNone;
        well_formed = linked;
    }
}

IntervalEvaluator::IntervalEvaluator(uint32_t max_regs, uint32_t max_choices)
    : max_regs_(std::max<uint32_t>(max_regs, 1)),
      max_choices_(max_choices),
      lo_store_(alloc_floats(size_t(max_regs_) * kIvLanes), &free_aligned),
      hi_store_(alloc_floats(size_t(max_regs_) * kIvLanes), &free_aligned),
      lo_(lo_store_.get()),
      hi_(hi_store_.get()),
      choices_(new uint8_t[size_t(max_choices) * kIvLanes + 64]) {}  // + 64: whole-vector reads past a row

void IntervalEvaluator::eval(const Tape& t, const float* xlo, const float* xhi, const float* ylo, const float* yhi,
                             const float* zlo, const float* zhi, int n, float time) {
    const int m = (n + 7) / 8 * 8;  // lanes computed (whole vectors); padding copies lane n-1
    stride_ = m;
    out_ = t.out;
    float* const L = lo_;
    float* const H = hi_;
    uint8_t* chp = choices_.get();
    auto input = [&](const Instr& in, const float* l, const float* h) {
        float* rl = L + size_t(in.out) * kIvLanes;
        float* rh = H + size_t(in.out) * kIvLanes;
        for (int i = 0; i < m; ++i) {
            int j = i < n ? i : n - 1;
            rl[i] = l[j];
            rh[i] = h[j];
        }
    };
    for (const Instr& in : t.code) {
        float* rl = L + size_t(in.out) * kIvLanes;
        float* rh = H + size_t(in.out) * kIvLanes;
        const float* al = L + size_t(in.a) * kIvLanes;
        const float* ah = H + size_t(in.a) * kIvLanes;
        const float* bl = L + size_t(in.b) * kIvLanes;
        const float* bh = H + size_t(in.b) * kIvLanes;
        const float* cl = L + size_t(in.c) * kIvLanes;
        const float* chh = H + size_t(in.c) * kIvLanes;
        const float k = in.k;
        switch (in.op) {
#define OP(name, mn, ar, imm, sem, glsl)                                                    \
    case Op::name:                                                                          \
        if constexpr (Op::name == Op::VarX) input(in, xlo, xhi);                            \
        else if constexpr (Op::name == Op::VarY) input(in, ylo, yhi);                       \
        else if constexpr (Op::name == Op::VarZ) input(in, zlo, zhi);                       \
        else if constexpr (Op::name == Op::Time) {                                          \
            std::fill_n(rl, m, time);                                                       \
            std::fill_n(rh, m, time);                                                       \
        } else {                                                                            \
            if constexpr (choice_op<Op::name>()) {                                          \
                SDFC_IVDEP                                                                  \
                for (int i = 0; i < m; ++i) {                                               \
                    uint8_t c;                                                              \
                    float lo, hi;                                                           \
                    iv<Op::name>(al[i], ah[i], bl[i], bh[i], cl[i], chh[i], k, lo, hi, c);  \
                    rl[i] = lo;                                                             \
                    rh[i] = hi;                                                             \
                    chp[i] = c;                                                             \
                }                                                                           \
                chp += m;                                                                   \
            } else {                                                                        \
                SDFC_IVDEP                                                                  \
                for (int i = 0; i < m; ++i) {                                               \
                    uint8_t c;                                                              \
                    float lo, hi;                                                           \
                    iv<Op::name>(al[i], ah[i], bl[i], bh[i], cl[i], chh[i], k, lo, hi, c);  \
                    rl[i] = lo;                                                             \
                    rh[i] = hi;                                                             \
                }                                                                           \
            }                                                                               \
        }                                                                                   \
        break;
#include "compiler/ir/opcodes.def"
#undef OP
        }
    }
}

void simplify(const Tape& parent, const uint8_t* choices, int stride, int lane, Tape& out, SimplifyScratch& s) {
    const size_t n = parent.code.size();
    out.code.clear();
    out.linked = false;
    out.well_formed = false;
    out.out = 0;
    out.num_regs = 1;
    out.choices = 0;
    if (n == 0 || parent.out_def == Tape::kNone || !parent.linked) {
        // The output is never written, or the tape reads unwritten registers: keep it as is.
        out.code = parent.code;
        out.out = parent.out;
        out.num_regs = parent.num_regs;
        out.choices = parent.choices;
        return;
    }
    const size_t words = (n + 63) / 64;
    s.live.assign(words, 0);
    if (s.bind.size() < n) s.bind.resize(n);
    if (s.free_regs.size() < n + 1) s.free_regs.resize(n + 1);
    if (s.rev.size() < n + 1) s.rev.resize(n + 1);
    Instr* rev = s.rev.data();
    size_t nrev = 0;
    uint16_t* free_regs = s.free_regs.data();
    size_t nfree = 0;
    uint16_t next = 0;
    uint32_t nch = 0;
    auto alloc = [&]() -> uint16_t { return nfree ? free_regs[--nfree] : next++; };
    auto release = [&](uint16_t r) { free_regs[nfree++] = r; };
    uint64_t* live = s.live.data();
    uint16_t* bind = s.bind.data();
    const uint8_t* cp = choices + lane;
    const Instr* code = parent.code.data();
    const Tape::Link* links = parent.links.data();
    // A decided choice op whose winner is a register is skipped: its users read the winner
    // directly (following chains of them).
    auto chase = [&](uint32_t d) -> uint32_t {
        for (;;) {
            const uint32_t sl = links[d].slot;
            if (sl == Tape::kNone) return d;
            const uint8_t ch = cp[size_t(sl) * size_t(stride)];
            if (ch == kChoiceBoth) return d;
            if (ch == kChoiceB && (code[d].op == Op::MinI || code[d].op == Op::MaxI)) return d;  // becomes a Const
            d = links[d].def[ch - 1];
        }
    };
    {
        const uint32_t o = chase(parent.out_def);
        live[o >> 6] |= uint64_t(1) << (o & 63);
        bind[o] = alloc();
    }
    // The register holding the value of instruction d, allocating one at its last use
    // (the first met walking backwards).
    auto use = [&](uint32_t d) -> uint16_t {
        d = chase(d);
        uint64_t& w = live[d >> 6];
        const uint64_t bit = uint64_t(1) << (d & 63);
        if (!(w & bit)) {
            w |= bit;
            bind[d] = alloc();
        }
        return bind[d];
    };
    for (size_t w = words; w-- > 0;) {
        uint64_t word;
        while ((word = live[w]) != 0) {
            const int b = 63 - __builtin_clzll(word);
            live[w] = word & ~(uint64_t(1) << b);
            const uint32_t i = uint32_t(w * 64 + size_t(b));
            const Instr in = code[i];
            const Tape::Link& l = links[i];
            const uint16_t X = bind[i];
            release(X);  // before the operands: the result may reuse an operand's register
            if (l.slot != Tape::kNone) {
                if (cp[size_t(l.slot) * size_t(stride)] != kChoiceBoth) {
                    // MinI/MaxI whose immediate wins (chase() stops there): a constant.
                    Instr c{Op::Const};
                    c.out = X;
                    c.k = in.k;
                    rev[nrev++] = c;
                    continue;
                }
                ++nch;
            }
            Instr e{in.op};
            e.out = X;
            e.k = in.k;
            // Operand a first: it gets the output's register when it dies here, so a later
            // trace (simplify_batch) of this tape needs no copy when a wins a choice (the
            // common case: the accumulated side of a min/max chain).
            const int ar = kOpInfo[int(in.op)].arity;
            if (ar >= 1) e.a = use(l.def[0]);
            if (ar >= 2) e.b = use(l.def[1]);
            if (ar >= 3) e.c = use(l.def[2]);
            rev[nrev++] = e;
        }
    }
    out.code.assign(std::make_reverse_iterator(rev + nrev), std::make_reverse_iterator(rev));
    out.out = 0;  // the output was bound first
    out.num_regs = std::max<uint32_t>(next, 1);
    out.choices = nch;
    out.well_formed = true;
    out.link();  // ready to be simplified further
}

namespace {

// Lanes (of the first 64) whose choice byte in `row` equals v.
inline uint64_t lanes_equal(const uint8_t* row, uint8_t v) {
#if defined(__SSE2__)
    const __m128i want = _mm_set1_epi8(char(v));
    uint64_t m = 0;
    for (int q = 0; q < 4; ++q) {
        __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + 16 * q));
        m |= uint64_t(uint32_t(_mm_movemask_epi8(_mm_cmpeq_epi8(x, want)) & 0xFFFF)) << (16 * q);
    }
    return m;
#else
    uint64_t m = 0;
    for (int i = 0; i < 64; ++i) m |= uint64_t(row[i] == v) << i;
    return m;
#endif
}

}  // namespace

void simplify_batch(const Tape& parent, const uint8_t* choices, int stride, uint64_t lanes, BatchScratch& s,
                    bool compact) {
    const size_t n = parent.code.size();
    s.len.fill(0);
    s.out.fill(0);
    s.cap = n;
    if (lanes == 0) return;
    const size_t blocks = size_t(64 - __builtin_clzll(lanes));  // lanes 0 .. the highest one used
    if (s.buf_size < blocks * n) {
        s.buf.reset(static_cast<Instr*>(::operator new(sizeof(Instr) * blocks * n)));
        s.buf_size = blocks * n;
    }
    Instr* buf = s.buf.get();
    if (!parent.linked || parent.out_def == Tape::kNone) {
        for (uint64_t m = lanes; m; m &= m - 1) {
            const int j = __builtin_ctzll(m);
            std::copy(parent.code.begin(), parent.code.end(), buf + size_t(j) * n);
            s.start[size_t(j)] = 0;
            s.len[size_t(j)] = uint32_t(n);
            s.regs[size_t(j)] = parent.num_regs;
            s.out[size_t(j)] = parent.out;
        }
        return;
    }
    // Backwards: the lanes in which each instruction's value is needed.
    if (s.mask.size() < n) s.mask.resize(n);
    uint64_t* need = s.mask.data();
    std::fill_n(need, n, uint64_t(0));
    need[parent.out_def] = lanes;
    const Instr* code = parent.code.data();
    const Tape::Link* links = parent.links.data();
    for (size_t i = n; i-- > 0;) {
        const uint64_t m = need[i];
        if (!m) continue;
        const Instr& in = code[i];
        const Tape::Link& l = links[i];
        const int ar = kOpInfo[int(in.op)].arity;
        if (l.slot == Tape::kNone) {
            if (ar > 0) need[l.def[0]] |= m;
            if (ar > 1) need[l.def[1]] |= m;
            if (ar > 2) need[l.def[2]] |= m;
            continue;
        }
        const uint8_t* row = choices + size_t(l.slot) * size_t(stride);
        const uint64_t ca = lanes_equal(row, kChoiceA), cb = lanes_equal(row, kChoiceB);
        const uint64_t cc = in.op == Op::Select ? lanes_equal(row, kChoiceC) : 0;
        const uint64_t both = m & ~(ca | cb | cc);
        need[l.def[0]] |= in.op == Op::Select ? both : (m & (ca | both));
        if (in.op == Op::Min || in.op == Op::Max || in.op == Op::Select) need[l.def[1]] |= m & (cb | both);
        if (in.op == Op::Select) need[l.def[2]] |= m & (cc | both);
    }
    if (!compact) {
        // Forwards: each lane's instructions in the parent's registers. A decided choice op
        // becomes a copy of the winner into its output register (nothing when the winner is
        // already there) or, for an immediate, a constant.
        std::array<uint32_t, 64> cnt{};
        for (size_t i = 0; i < n; ++i) {
            uint64_t m = need[i];
            if (!m) continue;
            const Instr in = code[i];
            const uint32_t sl = links[i].slot;
            if (sl == Tape::kNone) {
                for (; m; m &= m - 1) {
                    const size_t j = size_t(__builtin_ctzll(m));
                    buf[j * n + cnt[j]++] = in;
                }
                continue;
            }
            const uint8_t* row = choices + size_t(sl) * size_t(stride);
            for (; m; m &= m - 1) {
                const size_t j = size_t(__builtin_ctzll(m));
                const uint8_t ch = row[j];
                if (ch == kChoiceBoth) {
                    buf[j * n + cnt[j]++] = in;
                    continue;
                }
                Instr c{Op::Copy};
                c.out = in.out;
                if (ch == kChoiceB && (in.op == Op::MinI || in.op == Op::MaxI)) {
                    c.op = Op::Const;
                    c.k = in.k;
                } else {
                    c.a = ch == kChoiceA ? in.a : (ch == kChoiceB ? in.b : in.c);
                    if (c.a == c.out) continue;  // the winner is already in place
                }
                buf[j * n + cnt[j]++] = c;
            }
        }
        for (uint64_t lm = lanes; lm; lm &= lm - 1) {
            const size_t j = size_t(__builtin_ctzll(lm));
            s.start[j] = 0;
            s.len[j] = cnt[j];
            s.regs[j] = parent.num_regs;
            s.out[j] = parent.out;
        }
        return;
    }
    // Forwards: each lane's live instructions, as parent indices in order.
    if (s.idx_size < blocks * n) {
        s.idx.reset(new uint32_t[blocks * n]);
        s.idx_size = blocks * n;
    }
    uint32_t* idx = s.idx.get();
    std::array<uint32_t, 64> cnt{};
    for (size_t i = 0; i < n; ++i)
        for (uint64_t m = need[i]; m; m &= m - 1) {
            const size_t j = size_t(__builtin_ctzll(m));
            idx[j * n + cnt[j]++] = uint32_t(i);
        }
    // Per lane, backwards over its live instructions: registers re-allocated (linear scan;
    // an op's output may share a dying operand's register, which the lane-wise VM allows);
    // a decided choice op's winner takes over its output register (no instruction), or is
    // copied when it stays needed elsewhere; an immediate that wins becomes a constant.
    constexpr uint16_t kFree = 0xFFFF;
    const size_t nregs = std::max<size_t>(parent.num_regs, size_t(parent.out) + 1);
    if (s.bind.size() < nregs) s.bind.resize(nregs);
    if (s.free_regs.size() < n + 1) s.free_regs.resize(n + 1);
    uint16_t* bind = s.bind.data();
    uint16_t* free_regs = s.free_regs.data();
    for (uint64_t lm = lanes; lm; lm &= lm - 1) {
        const size_t j = size_t(__builtin_ctzll(lm));
        std::fill_n(bind, nregs, kFree);
        size_t nfree = 0;
        uint16_t next = 0;
        auto alloc = [&]() -> uint16_t { return nfree ? free_regs[--nfree] : next++; };
        Instr* out = buf + j * n + n;  // written backwards from the end of the lane's block
        size_t nout = 0;
        bind[parent.out] = alloc();
        const uint32_t* list = idx + j * n;
        for (size_t q = cnt[j]; q-- > 0;) {
            const uint32_t i = list[q];
            const Instr& in = code[i];
            const uint16_t X = bind[in.out];
            if (X == kFree) continue;  // (cannot happen: the lane needs every listed value)
            bind[in.out] = kFree;
            const uint32_t sl = links[i].slot;
            const uint8_t ch = sl == Tape::kNone ? uint8_t(kChoiceBoth) : choices[size_t(sl) * size_t(stride) + j];
            if (ch != kChoiceBoth) {
                if (ch == kChoiceB && (in.op == Op::MinI || in.op == Op::MaxI)) {
                    Instr c{Op::Const};
                    c.out = X;
                    c.k = in.k;
                    *--out = c;
                    ++nout;
                    free_regs[nfree++] = X;
                    continue;
                }
                const uint16_t w = ch == kChoiceA ? in.a : (ch == kChoiceB ? in.b : in.c);
                if (bind[w] == kFree) {
                    bind[w] = X;  // the winner's value lives in X: no instruction
                } else {
                    Instr c{Op::Copy};
                    c.out = X;
                    c.a = bind[w];
                    *--out = c;
                    ++nout;
                    free_regs[nfree++] = X;
                }
                continue;
            }
            free_regs[nfree++] = X;  // before the operands: the result may reuse one's register
            Instr e{in.op};
            e.out = X;
            e.k = in.k;
            {
                // Operand a first: it gets the output's register when it dies here (see simplify()).
                const int ar = kOpInfo[int(in.op)].arity;
                if (ar >= 1) {
                    if (bind[in.a] == kFree) bind[in.a] = alloc();
                    e.a = bind[in.a];
                }
                if (ar >= 2) {
                    if (bind[in.b] == kFree) bind[in.b] = alloc();
                    e.b = bind[in.b];
                }
                if (ar >= 3) {
                    if (bind[in.c] == kFree) bind[in.c] = alloc();
                    e.c = bind[in.c];
                }
            }
            *--out = e;
            ++nout;
        }
        s.start[j] = uint32_t(n - nout);
        s.len[j] = uint32_t(nout);
        s.regs[j] = std::max<uint32_t>(next, 1);
    }
}

void Tape::assign(const Instr* c, size_t count, uint16_t out_reg, uint32_t regs) {
    code.assign(c, c + count);
    out = out_reg;
    num_regs = regs;
    linked = false;
    well_formed = true;  // simplify_batch's output
    links.clear();
    out_def = kNone;
}

}  // namespace sdfc
