// Interval semantics of every opcode and the batch interval evaluator.
//
// Exactness. The VM's arithmetic is IEEE single precision with round-to-nearest, which is
// monotonic: x <= y implies fl(x) <= fl(y). So for an op that is monotonic in each operand
// and rounds once (add, sub, mul, min, max, sqrt, square, ...), computing the interval's
// ends with the same float operation as the VM gives bounds that enclose the VM's results
// exactly, with no outward rounding. Ops whose VM form may round more than once, or may be
// contracted into an FMA by the compiler (MulAddI, Mix, Length2/3, Mod), and the
// transcendentals (om::exp_ and the like, not proven monotonic to the ulp) are widened by a
// few ulps. Min/max choices compare the interval ends with the same comparisons the VM's
// om::min_ / om::max_ make, so a decided choice is the VM's choice at every point.
#include "runtime/eval/interval.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <new>
#include <span>

#include "runtime/eval/isa.hpp"
#include "runtime/eval/simd.hpp"

// A new opcode must get its interval semantics here: a missing case is an error.
#pragma GCC diagnostic error "-Wswitch"

namespace sdfc {
namespace {

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
// Wider, for the transcendentals (om::exp_ and kin: a few ulps, not proven monotonic).
SDFC_IV_INLINE float dnw(float x) { return x - margin(x, 0x1p-18f, 0x1p-120f); }
SDFC_IV_INLINE float upw(float x) { return x + margin(x, 0x1p-18f, 0x1p-120f); }

SDFC_IV_INLINE float mn(float a, float b) { return b < a ? b : a; }
SDFC_IV_INLINE float mx(float a, float b) { return a < b ? b : a; }

// 0 for a finite value, NaN for an infinite or NaN one: added to both ends of a result, it
// turns the result unknown when an operand may be infinite or NaN.
SDFC_IV_INLINE float poison(float lo, float hi) { return (lo - lo) + (hi - hi); }

// The NaN that infinite operand ends can make (None-poison ops check for their own):
// [al, ah] + [bl, bh] meets +inf + -inf; [al, ah] * [bl, bh] meets 0 * inf.
SDFC_IV_INLINE bool infinite_end(float l, float h) { return std::isinf(l) | std::isinf(h); }
SDFC_IV_INLINE float unknown(float l, float h) { return (std::isnan(l) | std::isnan(h)) ? kNaN : 0.0f; }
SDFC_IV_INLINE bool opposite_infinities(float al, float ah, float bl, float bh) {
    return ((ah == kInf) & (bl == -kInf)) | ((al == -kInf) & (bh == kInf));
}
SDFC_IV_INLINE bool zero_times_infinity(float al, float ah, float bl, float bh) {
    const bool a0 = (al <= 0.0f) & (ah >= 0.0f), b0 = (bl <= 0.0f) & (bh >= 0.0f);
    return (a0 & infinite_end(bl, bh)) | (b0 & infinite_end(al, ah));
}

// |v| over [l, h]: the least and the greatest.
SDFC_IV_INLINE void abs_ends(float l, float h, float& lo, float& hi) {
    lo = l >= 0.0f ? l : (h <= 0.0f ? -h : 0.0f);
    hi = mx(-l, h);
}

// The length of (a, b) or, Three, (a, b, c): Length2's and Length3's interval.
template <bool Three>
SDFC_IV_INLINE void length_iv(float al, float ah, float bl, float bh, float cl, float ch, float& lo, float& hi) {
    float a0, a1, b0, b1;
    abs_ends(al, ah, a0, a1);
    abs_ends(bl, bh, b0, b1);
    float s0 = a0 * a0 + b0 * b0, s1 = a1 * a1 + b1 * b1;
    if constexpr (Three) {
        float c0, c1;
        abs_ends(cl, ch, c0, c1);
        s0 += c0 * c0;
        s1 += c1 * c1;
    }
    lo = mx(dn(std::sqrt(s0)), 0.0f);
    hi = up(std::sqrt(s1));
}

// [l, h] + k (AddI, and the fused length ops after their length): the VM's rounded add is
// monotonic, so the ends' sums bound it; z turns NaN for inf - inf or a NaN k.
SDFC_IV_INLINE void add_k_iv(float l, float h, float k, float& lo, float& hi, float& z) {
    lo = l + k;
    hi = h + k;
    z += opposite_infinities(l, h, k, k) ? kNaN : 0.0f;
    z += std::isnan(k) ? kNaN : 0.0f;
}

// Interval product (corners); no NaN for finite operands.
SDFC_IV_INLINE void mul_iv(float al, float ah, float bl, float bh, float& lo, float& hi) {
    float p0 = al * bl, p1 = al * bh, p2 = ah * bl, p3 = ah * bh;
    lo = mn(mn(p0, p1), mn(p2, p3));
    hi = mx(mx(p0, p1), mx(p2, p3));
}

// Monotonic transcendental, increasing.
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

// Unknown intervals. Invariant: if a point of the box may give NaN, or the interval is
// unknown, both ends are NaN; NaN ends never decide a choice (comparisons are false). An
// op keeps it by adding z (0, or NaN) to both ends, z from its poison kind: opcodes.def's
// poison column (OpPoison in compiler/ir/opcodes.hpp says what each kind means).
using Poison = OpPoison;
template <Op O>
constexpr Poison poison_kind() { return kOpInfo[int(O)].poison; }

// The interval semantics of op O: [al, ah] etc. in, [lo, hi] and the choice out.
template <Op O>
SDFC_IV_INLINE void iv(float al, float ah, float bl, float bh, float cl, float ch, float k, float& lo, float& hi,
                       int& choice) {  // (an int, not a byte: lane loops of one element width vectorise best)
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
        z = (std::isnan(bl) | std::isnan(bh)) ? kNaN : 0.0f;
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
            z += unknown(al, ah);  // the comparisons above drop NaN ends
            break;
        case Op::Square: {
            float l2 = al * al, h2 = ah * ah;
            lo = al >= 0.0f ? l2 : (ah <= 0.0f ? h2 : 0.0f);
            hi = al >= 0.0f ? h2 : (ah <= 0.0f ? l2 : mx(l2, h2));
            z += unknown(al, ah);
            break;
        }
        case Op::Sqrt:
            lo = std::sqrt(mx(al, 0.0f));
            hi = std::sqrt(mx(ah, 0.0f));
            z += al < 0.0f ? kNaN : 0.0f;  // some point may take the root of a negative number
            break;
        case Op::Sin: sin_iv(al, ah, kPi / 2, om::sin_, lo, hi); break;
        case Op::Cos: sin_iv(al, ah, 0.0f, om::cos_, lo, hi); break;
        case Op::Tan: {
            // Monotonic between asymptotes at pi/2 + pi n.
            const double pi = 3.141592653589793;
            bool ok = ah - al < 3.0f && std::fabs(al) < 1e5f && std::fabs(ah) < 1e5f &&
                      std::floor((double(ah) + 1e-3 - pi / 2) / pi) < std::ceil((double(al) - 1e-3 - pi / 2) / pi);
            lo = ok ? dnw(om::tan_(al)) : -kInf;
            hi = ok ? upw(om::tan_(ah)) : kInf;
            break;
        }
        case Op::Asin:
            mono_inc([](float v) { return om::asin_(om::clamp1(v)); }, al, ah, lo, hi);
            break;
        case Op::Acos:
            lo = dnw(om::acos_(om::clamp1(ah)));
            hi = upw(om::acos_(om::clamp1(al)));
            break;
        case Op::Atan: mono_inc([](float v) { return om::atan_(v); }, al, ah, lo, hi); break;
        case Op::Exp:
            mono_inc([](float v) { return om::exp_(v); }, al, ah, lo, hi);
            lo = mx(lo, 0.0f);
            break;
        case Op::Log:
            mono_inc([](float v) { return om::log_(v); }, mx(al, 0.0f), mx(ah, 0.0f), lo, hi);
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
        case Op::Add:
            lo = al + bl;
            hi = ah + bh;
            z += opposite_infinities(al, ah, bl, bh) ? kNaN : 0.0f;
            break;
        case Op::Sub:
            lo = al - bh;
            hi = ah - bl;
            z += opposite_infinities(al, ah, -bh, -bl) ? kNaN : 0.0f;
            break;
        case Op::Mul:
            mul_iv(al, ah, bl, bh, lo, hi);
            z += zero_times_infinity(al, ah, bl, bh) ? kNaN : 0.0f;
            break;
        case Op::Div: {
            float q0 = al / bl, q1 = al / bh, q2 = ah / bl, q3 = ah / bh;
            lo = mn(mn(q0, q1), mn(q2, q3));
            hi = mx(mx(q0, q1), mx(q2, q3));
            z += ((bl > 0.0f) | (bh < 0.0f)) ? 0.0f : kNaN;  // the divisor may be zero
            z += (infinite_end(al, ah) & infinite_end(bl, bh)) ? kNaN : 0.0f;  // inf / inf
            break;
        }
        case Op::Min:
            // om::min_(a, b) = b < a ? b : a
            lo = mn(al, bl);
            hi = mn(ah, bh);
            choice = int((ah <= bl) * kChoiceA + (bh < al) * kChoiceB);  // exclusive
            break;
        case Op::Max:
            // om::max_(a, b) = a < b ? b : a
            lo = mx(al, bl);
            hi = mx(ah, bh);
            choice = int((ah < bl) * kChoiceB + (bh <= al) * kChoiceA);
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
            float p0 = om::pow_(al, bl), p1 = om::pow_(al, bh), p2 = om::pow_(ah, bl), p3 = om::pow_(ah, bh);
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
        case Op::Length2: length_iv<false>(al, ah, bl, bh, cl, ch, lo, hi); break;
        case Op::Length3: length_iv<true>(al, ah, bl, bh, cl, ch, lo, hi); break;
        case Op::Length2I:
        case Op::Length3I: {
            // Length2 / Length3's interval, then AddI's.
            float l0, l1;
            length_iv<O == Op::Length3I>(al, ah, bl, bh, cl, ch, l0, l1);
            add_k_iv(l0, l1, k, lo, hi, z);
            break;
        }
        case Op::AddI: add_k_iv(al, ah, k, lo, hi, z); break;
        case Op::SubI:
            lo = k - ah;
            hi = k - al;
            z += opposite_infinities(k, k, -ah, -al) ? kNaN : 0.0f;
            z += std::isnan(k) ? kNaN : 0.0f;
            break;
        case Op::MulI: {
            float p = al * k, q = ah * k;
            lo = mn(p, q);
            hi = mx(p, q);
            z += zero_times_infinity(al, ah, k, k) ? kNaN : 0.0f;
            z += std::isnan(k) ? kNaN : 0.0f;
            break;
        }
        case Op::DivI: {
            float p = k / al, q = k / ah;
            lo = mn(p, q);
            hi = mx(p, q);
            z += ((al > 0.0f) | (ah < 0.0f)) ? 0.0f : kNaN;
            z += (std::isinf(k) & infinite_end(al, ah)) ? kNaN : 0.0f;  // inf / inf
            z += std::isnan(k) ? kNaN : 0.0f;
            break;
        }
        case Op::MinI:
            // om::min_(a, k) = k < a ? k : a
            lo = mn(al, k);
            hi = mn(ah, k);
            choice = int((ah <= k) * kChoiceA + (k < al) * kChoiceB);
            break;
        case Op::MaxI:
            // om::max_(a, k) = a < k ? k : a
            lo = mx(al, k);
            hi = mx(ah, k);
            choice = int((ah < k) * kChoiceB + (k <= al) * kChoiceA);
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
            float pl = om::pow_(al, k), ph = om::pow_(ah, k);
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
            choice = int(t * kChoiceB + f * kChoiceC);
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
        case Op::Guard: lo = hi = INFINITY; break;  // overwritten by its region
        case Op::Param: lo = -INFINITY; hi = INFINITY; break;  // a shader's uniform
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

// The choice of a sign-only min/max (kSignOnly, runtime/eval/tape.hpp) over a box, given
// the value choice c: only "result < 0" matters, so
//   min(a, b) < 0  is  a < 0 or b < 0:   a < 0 throughout -> a;  a >= 0 throughout -> b
//   max(a, b) < 0  is  a < 0 and b < 0:  a >= 0 throughout -> a; a < 0 throughout -> b
// (and the same with a and b swapped). The VM's min_/max_ with a NaN operand do not follow
// these, so both operands must be known (not NaN); an immediate decides alone.
template <Op O>
SDFC_IV_INLINE int sign_choice(int c, float al, float ah, float bl, float bh, float k) {
    if constexpr (O == Op::Min || O == Op::Max) {
        const bool known = (al == al) & (ah == ah) & (bl == bl) & (bh == bh);
        const bool neg_a = ah < 0.0f, neg_b = bh < 0.0f, pos_a = al >= 0.0f, pos_b = bl >= 0.0f;
        const bool pick_a = O == Op::Min ? (neg_a | pos_b) : (pos_a | neg_b);
        const bool pick_b = O == Op::Min ? (neg_b | pos_a) : (pos_b | neg_a);
        const int s = pick_a ? int(kChoiceA) : (pick_b ? int(kChoiceB) : int(kChoiceBoth));
        return c != kChoiceBoth ? c : (known ? s : c);
    } else if constexpr (O == Op::MinI || O == Op::MaxI) {
        // A winner must also be NaN where the op is (a sign-only user's min_/max_ takes a NaN
        // operand as it takes no number: max_(x, NaN) is x, max_(x, 0) is 0). min_(a, k) and
        // max_(a, k) are NaN exactly where a is, so a wins whenever it has the op's sign:
        //   min: k >= 0 -> a;  max: k < 0 -> a.
        // The immediate only where a is never NaN (known): min: k < 0 -> k;  max: k >= 0 -> k.
        const bool known = (al == al) & (ah == ah);
        const bool to_a = O == Op::MinI ? k >= 0.0f : k < 0.0f;
        const bool to_k = O == Op::MinI ? k < 0.0f : k >= 0.0f;
        return c != kChoiceBoth ? c : (to_a ? int(kChoiceA) : (to_k & known ? int(kChoiceB) : c));
    } else {
        return c;
    }
}

}  // namespace

// The kernel for each instruction set the build carries (runtime/eval/isa.hpp).
namespace iv_baseline {
#include "runtime/eval/interval_kernel.inl"
}  // namespace iv_baseline
#if defined(SDFC_ISA_DISPATCH)
SDFC_ISA_BEGIN_AVX2
namespace iv_avx2 {
#include "runtime/eval/interval_kernel.inl"
}  // namespace iv_avx2
SDFC_ISA_END
SDFC_ISA_BEGIN_AVX512
namespace iv_avx512 {
#include "runtime/eval/interval_kernel.inl"
}  // namespace iv_avx512
SDFC_ISA_END
#endif

namespace {
using RunFn = void (*)(const TapeView&, float*, float*, uint8_t*, float*, uint8_t*, const float*, const float*, const float*,
                       const float*, const float*, const float*, int, int, float);
const RunFn kKernels[] = {
    iv_baseline::run,
#if defined(SDFC_ISA_DISPATCH)
    iv_avx2::run,
    iv_avx512::run,
#endif
};
RunFn kernels() {
    const int i = static_cast<int>(current_isa());
    return kKernels[i < int(std::size(kKernels)) ? i : 0];
}
}  // namespace

Interval eval_interval(Op op, Interval a, Interval b, Interval c, float k, uint8_t* choice) {
    Interval r{};
    int ch = kChoiceBoth;
    switch (op) {
#define OP(name, mn, ar, imm, choice_, poison_, sem, glsl) \
    case Op::name: iv<Op::name>(a.lo, a.hi, b.lo, b.hi, c.lo, c.hi, k, r.lo, r.hi, ch); break;
#include "compiler/ir/opcodes.def"
#undef OP
    }
    if (choice) *choice = uint8_t(ch);
    return r;
}

IntervalEvaluator::IntervalEvaluator(uint32_t max_regs, uint32_t max_choices)
    : max_regs_(std::max<uint32_t>(max_regs, 1)),
      max_choices_(max_choices),
      lo_store_(alloc_floats(size_t(max_regs_) * kIvLanes), &free_aligned),
      hi_store_(alloc_floats(size_t(max_regs_) * kIvLanes), &free_aligned),
      lo_(lo_store_.get()),
      hi_(hi_store_.get()),
      choices_(new uint8_t[size_t(max_choices) * kIvLanes + 64]) {}  // + 64: whole-vector reads past a row

void IntervalEvaluator::reserve(uint32_t regs, uint32_t choices) {
    if (regs > max_regs_) {
        lo_store_.reset(alloc_floats(size_t(regs) * kIvLanes));
        hi_store_.reset(alloc_floats(size_t(regs) * kIvLanes));
        lo_ = lo_store_.get();
        hi_ = hi_store_.get();
        max_regs_ = regs;
    }
    if (choices > max_choices_) {
        choices_.reset(new uint8_t[size_t(choices) * kIvLanes + 64]);
        max_choices_ = choices;
    }
}

void IntervalEvaluator::eval(const TapeView& t, const float* xlo, const float* xhi, const float* ylo, const float* yhi,
                             const float* zlo, const float* zhi, int n, float time) {
    uint32_t nch = t.choices;
    if (nch == TapeView::kUncounted) {
        nch = 0;
        for (uint32_t i = 0; i < t.len; ++i) nch += is_choice_op(t.code[i].op);
    }
    reserve(t.num_regs, nch);
    const int m = (n + 15) / 16 * 16;  // lanes computed (whole vectors); padding copies lane n-1
    stride_ = m;
    out_ = t.output(0);
    float* cv = nullptr;
    if (keep_chains_) {
        if (chain_.size() < size_t(nch) * 4 * size_t(m)) chain_.resize(size_t(nch) * 4 * size_t(m));
        cv = chain_.data();
        std::fill_n(chain_unknown_, kIvLanes, uint8_t(0));
    }
    kernels()(t, lo_, hi_, choices_.get(), cv, chain_unknown_, xlo, xhi, ylo, yhi, zlo, zhi, n, m, time);
}

namespace {

// prune_min_chains' update of one chain min's lanes (see there), in whole rows of 16 lanes
// (m is a multiple of 16); ok: the lanes to update. Its own function, with restrict
// pointers and no branch per lane, so that GCC vectorises it.
void prune_rows(const float* __restrict cv, uint8_t* __restrict chr, const float* __restrict B, float* __restrict ba,
                float* __restrict bb, const int32_t* __restrict ok, size_t m) {
    for (size_t j0 = 0; j0 < m; j0 += 16) {
        alignas(64) int32_t cw[16];
        for (size_t q = 0; q < 16; ++q) cw[q] = chr[j0 + q];
        for (size_t q = 0; q < 16; ++q) {
            const size_t j = j0 + q;
            const float al = cv[j], ah = cv[m + j], bl = cv[2 * m + j], bh = cv[3 * m + j];
            const float for_a = mn(bh, B[j]), for_b = mn(ah, B[j]);  // bounds of the rest, seen from a and from b
            const int32_t c = cw[q], k = ok[j];
            const int32_t undecided = k & int32_t(c == kChoiceBoth);
            const int32_t to_b = undecided & int32_t(al > for_a), to_a = undecided & ~to_b & int32_t(bl > for_b);
            // (arithmetic, not a ternary chain: GCC if-converts this one)
            const int32_t d = c + to_b * (int32_t(kChoiceB) - c) + to_a * (int32_t(kChoiceA) - c);
            cw[q] = d;
            const float xa = ba[j], xb = bb[j], ua = mn(xa, for_a), ub = mn(xb, for_b);
            const bool wa = (k & int32_t(d != kChoiceB)) != 0, wb = (k & int32_t(d != kChoiceA)) != 0;
            ba[j] = wa ? ua : xa;
            bb[j] = wb ? ub : xb;
        }
        for (size_t q = 0; q < 16; ++q) chr[j0 + q] = uint8_t(cw[q]);
    }
}

}  // namespace

// Top-down over the chain: bound[i] is an upper bound, over the box, of the rest of the
// chain around Min i (what the output would be without i's value); an operand whose lower
// bound exceeds min(bound, its sibling's upper bound) can never be the output. Dropping
// several at once keeps the output's floats: the operand with the least upper bound of all
// is never dropped and is below every dropped one at every point, and min() selects.
// Unknown (NaN) intervals anywhere in a lane's chain leave that lane alone (the VM's min
// with a NaN operand depends on the order).
void IntervalEvaluator::prune_min_chains(const Tape& t, int n) {
    if (!keep_chains_ || !t.linked || t.out_def == Tape::kNone) return;
    const size_t len = t.code.size(), m = size_t(stride_);
    if (!is_chain_min(t.code[t.out_def])) return;
    uint64_t bad = 0;  // lanes with an unknown interval in the chain
    for (int j = 0; j < n; ++j) bad |= uint64_t(chain_unknown_[j] != 0) << j;
    if (bad == (n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1)) return;
    bound_.assign(size_t(t.choices) * m, kInf);  // per choice slot
    uint8_t* choices = choices_.get();
    // Lanes to update (known, and not padding), as ints beside the floats: the loop below
    // then vectorises in whole rows (m is a multiple of 16), without a branch per lane.
    alignas(64) int32_t ok[kIvLanes];
    for (size_t j = 0; j < m; ++j) ok[j] = j < size_t(n) && chain_unknown_[j] == 0;
    // An operand that is not a chain min has no bound: its updates go to a sink row.
    alignas(64) float sink_a[kIvLanes], sink_b[kIvLanes];
    auto bound_of = [&](uint32_t d, float* sink) {
        return is_chain_min(t.code[d]) ? bound_.data() + size_t(t.links[d].slot) * m : sink;
    };
    for (size_t i = len; i-- > 0;) {
        if (!is_chain_min(t.code[i])) continue;
        const Tape::Link& l = t.links[i];
        const float* cv = chain_.data() + size_t(l.slot) * 4 * m;
        uint8_t* chr = choices + size_t(l.slot) * m;
        const float* B = bound_.data() + size_t(l.slot) * m;
        float* Ba = bound_of(l.def[0], sink_a);
        float* Bb = bound_of(l.def[1], sink_b);
        if (Ba == Bb) {  // min(x, x), x a chain min: lane by lane (the updates meet)
            for (int j = 0; j < n; ++j) {
                if (!ok[j]) continue;
                const float al = cv[j], ah = cv[m + j], bl = cv[2 * m + j], bh = cv[3 * m + j];
                const float for_a = mn(bh, B[j]), for_b = mn(ah, B[j]);
                if (chr[j] == kChoiceBoth) {
                    if (al > for_a) chr[j] = kChoiceB;
                    else if (bl > for_b) chr[j] = kChoiceA;
                }
                if (chr[j] != kChoiceB) Ba[j] = mn(Ba[j], for_a);
                if (chr[j] != kChoiceA) Bb[j] = mn(Bb[j], for_b);
            }
            continue;
        }
        prune_rows(cv, chr, B, Ba, Bb, ok, m);
    }
}

}  // namespace sdfc
