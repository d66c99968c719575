// View-independent depth-format audit: resolution, distinct values, fight distances, range.
// Every number is measured by calling the format's own encoder (render/depth_format.h); the
// closed forms are computed alongside only to compare. Derivations: docs/depth-formats.md.
#include "analysis/audits/depth_audit.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "render/depth_format_impl.h"

namespace va {

namespace {

constexpr double kC31 = 2147483647.0;  // 2^31 - 1, int31_inv's numerator
constexpr double kC32 = 4294967295.0;  // 2^32 - 1, uint32_inv's and uint32_inv1's numerator

// The unorm scale S = 2^N - 1 of the integer-normalized formats (0 for the others).
double unormScale(DepthFormat f) {
    switch (f) {
    case DepthFormat::unorm16:
    case DepthFormat::unorm16_reversed: return 65535.0;
    case DepthFormat::unorm24:
    case DepthFormat::unorm24_reversed:
    case DepthFormat::depth24plus:
    case DepthFormat::unorm24_gl:
    case DepthFormat::log24: return 16777215.0;
    default: return 0;
    }
}

// Formats whose encoder clamps d to [n, f]: depths beyond far store far's value, so far's stored
// value is the last one the format produces. The others map (n, +inf) without an upper clamp.
bool clampsAtFar(DepthFormat f) {
    switch (f) {
    case DepthFormat::unorm16:
    case DepthFormat::unorm24:
    case DepthFormat::unorm24_gl:
    case DepthFormat::f32:
    case DepthFormat::f32_reversed:
    case DepthFormat::log24:
    case DepthFormat::unorm16_reversed:
    case DepthFormat::unorm24_reversed:
    case DepthFormat::f32_gl:
    case DepthFormat::f32_gl_reversed:
    case DepthFormat::depth32float:
    case DepthFormat::depth24plus: return true;
    default: return false;
    }
}

float floatFromBits(uint32_t u) {
    float v;
    std::memcpy(&v, &u, 4);
    return v;
}

// The spacing from the float x (>= 0) to its neighbor above (up = true) or below: 2^(e-23) for a
// normal x in [2^e, 2^(e+1)) going up, and going down too except at x = 2^e exactly, where the
// binade below is twice as fine (2^(e-24)); 2^-149 among subnormals.
double floatSpacing(double x, bool up) {
    const float v = float(x);
    return std::fabs(double(std::nextafter(v, up ? INFINITY : -INFINITY)) - double(v));
}

// Non-negative doubles ordered by their bit patterns (IEEE-754: the order of the patterns of
// non-negative doubles is the order of the values), so bisection can run over "every double".
uint64_t doubleBits(double x) {
    uint64_t u;
    std::memcpy(&u, &x, 8);
    return u;
}
double doubleFromBits(uint64_t u) {
    double x;
    std::memcpy(&x, &u, 8);
    return x;
}

// The depth limits the bucket searches run within: below `lo` the encoder clamps to lo's value
// (the format's minimum valid depth: n, 1 or 0); above `hi` to hi's value (far for the formats
// that clamp there, else the largest double, where every format has long saturated).
struct SearchLimits {
    double lo, hi;
};
SearchLimits searchLimits(const DepthEncoder &e) {
    return {e.minValidDepth, clampsAtFar(e.format) ? e.farZ : DBL_MAX};
}

// Smallest double x in (d, hi] with key(x) > k, where key(d) == k; nullopt when key(hi) <= k
// (d's stored value is the format's last). Bisection over the bit patterns keeps the invariant
// key(lo) <= k < key(hi): 64 halvings at most, and the answer is exact to the last double.
std::optional<double> firstDepthBeyond(const DepthEncoder &e, double d, uint32_t k, double hi) {
    if (!(hi > d) || depthKey(e, hi) <= k) return std::nullopt;
    uint64_t a = doubleBits(d), b = doubleBits(hi);
    while (b - a > 1) {
        const uint64_t m = a + (b - a) / 2;
        if (depthKey(e, doubleFromBits(m)) > k) b = m;
        else a = m;
    }
    return doubleFromBits(b);
}

// Largest double x in [lo, d) with key(x) < k, where key(d) == k; nullopt when key(lo) >= k
// (d's stored value is the format's first). Invariant key(a) < k <= key(b).
std::optional<double> lastDepthBefore(const DepthEncoder &e, double d, uint32_t k, double lo) {
    if (!(lo < d) || depthKey(e, lo) >= k) return std::nullopt;
    uint64_t a = doubleBits(lo), b = doubleBits(d);
    while (b - a > 1) {
        const uint64_t m = a + (b - a) / 2;
        if (depthKey(e, doubleFromBits(m)) < k) a = m;
        else b = m;
    }
    return doubleFromBits(a);
}

// The closed-form resolution at d: |d depth / d stored| times the stored value's spacing there,
// taken in the same direction as the measured step (towardsFar: towards the next stored value, else
// the previous), so that a float at a power of two is compared with the spacing on its own side.
// ulp(s) below is that spacing. With z the normalized value and S the integer scale
// (docs/depth-formats.md derives each):
//   linear_f32        ulp(float(d))
//   inv_f32           s = 1/d, |dd/ds| = d^2:                  d^2 ulp(s)
//   int31_inv         s = C/d, |dd/ds| = d^2/C:                d^2 / (2^31 - 1)
//   uint32_inv        d^2 / (2^32 - 1);  uint32_inv1: (d + 1)^2 / (2^32 - 1)
//   unorm*, *_gl      z = f(d-n)/(d(f-n)), dz/dd = fn/((f-n)d^2): d^2 (f-n) / (S f n)
//   unorm*_reversed   z = n(f-d)/(d(f-n)), |dz/dd| the same:   d^2 (f-n) / (S f n)
//   f32, depth32float ulp(z) d^2 (f-n) / (f n)
//   f32_reversed      z = n(f-d)/(d(f-n)), |dz/dd| = nf/((f-n)d^2): ulp(z) d^2 (f-n) / (n f)
//   f32_reversed_inf  z = n/d: ulp(z) d^2 / n
//   f32_gl(_reversed) as f32 (f32_reversed) with the spacing max(ulp(w), ulp(z_ndc)/2): the window
//                     depth w = (z_ndc + 1)/2 cannot move by less than half a step of z_ndc
//   log24             s/S = ln(Cd+1)/L, ds/dd = S C/(L(Cd+1)):  L (C d + 1) / (S C)
double closedFormResolution(const DepthEncoder &e, double d, double stored, bool towardsFar) {
    const double n = e.nearZ, f = e.farZ, S = unormScale(e.format);
    // Towards far a float's stored value grows when nearer is smaller (linear_f32, f32) and shrinks
    // when nearer is larger (inv_f32, f32_reversed, f32_reversed_inf).
    const bool up = towardsFar != depthFormatInfo(e.format).nearerIsLarger;
    auto floatUlp = [up](double x) { return floatSpacing(x, up); };
    // The window depth's spacing in the OpenGL float formats: z_ndc = 2w - 1 moves with w.
    auto glUlp = [&](double w) { return std::max(floatUlp(w), 0.5 * floatUlp(2 * w - 1)); };
    switch (e.format) {
    case DepthFormat::linear_f32: return floatUlp(d);
    case DepthFormat::inv_f32: return d * d * floatUlp(stored);
    case DepthFormat::int31_inv: return d * d / kC31;
    case DepthFormat::uint32_inv: return d * d / kC32;
    case DepthFormat::uint32_inv1: return (d + 1) * (d + 1) / kC32;
    case DepthFormat::unorm16:
    case DepthFormat::unorm24:
    case DepthFormat::unorm24_gl:
    case DepthFormat::unorm16_reversed:
    case DepthFormat::unorm24_reversed:
    case DepthFormat::depth24plus: return d * (d / n) * ((f - n) / f) / S;
    case DepthFormat::f32:
    case DepthFormat::depth32float: return floatUlp(stored) * d * (d / n) * ((f - n) / f);
    case DepthFormat::f32_reversed: return floatUlp(stored) * d * (d / n) * ((f - n) / f);
    case DepthFormat::f32_gl:
    case DepthFormat::f32_gl_reversed: return glUlp(stored) * d * (d / n) * ((f - n) / f);
    case DepthFormat::f32_reversed_inf: return floatUlp(stored) * d * (d / n);
    case DepthFormat::log24: return e.logDenominator * (e.logC * d + 1) / (S * e.logC);
    }
    return NAN;
}

std::optional<double> finiteOrNone(double v) {
    if (std::isfinite(v)) return v;
    return std::nullopt;
}

DepthResolutionSample resolutionAt(const DepthEncoder &e, double d) {
    DepthResolutionSample s;
    s.depth = d;
    bool oor = false;
    s.key = depthKey(e, d, &oor);
    s.stored = depthStoredValue(e, d);
    s.inRange = !oor;
    if (oor) return s;
    const SearchLimits lim = searchLimits(e);

    // The neighbors: the stored values of the first double depth past each end of d's bucket.
    const std::optional<double> beyond = firstDepthBeyond(e, d, s.key, lim.hi);
    const std::optional<double> before = lastDepthBefore(e, d, s.key, lim.lo);
    if (beyond) s.stepToNext = finiteOrNone(depthBetweenStored(e, s.stored, depthStoredValue(e, *beyond)));
    if (before) s.stepToPrev = finiteOrNone(depthBetweenStored(e, depthStoredValue(e, *before), s.stored));
    s.resolution = s.stepToNext ? s.stepToNext : s.stepToPrev;
    if (s.stepToNext) s.skipsValues = depthKey(e, *beyond) - s.key > 1;
    else if (s.stepToPrev) s.skipsValues = s.key - depthKey(e, *before) > 1;

    // The bucket [first double storing v, first double past it), cut at the search limits.
    // Both ends are "first double of": the bucket's and the next one's (past the limit when d's
    // value is the last: the clamped bucket [.., hi] ends just past hi).
    const double bucketLo = before ? std::nextafter(*before, INFINITY) : lim.lo;
    const double bucketHi = beyond ? *beyond : std::nextafter(lim.hi, INFINITY);
    s.bucketWidth = finiteOrNone(bucketHi - bucketLo);

    s.closedForm = finiteOrNone(closedFormResolution(e, d, s.stored, s.stepToNext.has_value()));
    if (s.resolution && s.closedForm && *s.closedForm > 0)
        s.relativeDifference = finiteOrNone(*s.resolution / *s.closedForm - 1);
    return s;
}

// ---- The bucket model --------------------------------------------------------------------------
// Keys run in depth order (smaller = nearer) from kFirst, the key of the search range's start lo,
// to kLast, the key of its end hi. threshold(k), for kFirst < k <= kLast, is the value of the
// format's real-number mapping at which depth moves from key k-1 to key k (a "threshold value",
// in the variable the format rounds); depthAt(t) maps it back to depth through the exact inverse
// and widthBetween(t1, t2) = depthAt(t2) - depthAt(t1) without cancellation (docs/depth-formats.md):
//   unorm (standard)  t = k - 1/2 (S z scale)            d = f n / (f (S-t)/S + (t/S) n)
//   unorm_reversed    t = S - k + 1/2 (S z_rev scale)    d = n f / ((t/S)(f-n) + n)
//   log24             t = k - 1/2                        d = expm1(L t/S)/C
//   int31_inv         t = C31 - k + 1 (C/d = v + 1)      d = C31/t
//   uint32_inv(1)     t = 2^32 - k                       d = C32/t (minus 1 for uint32_inv1)
//   floats            t = the midpoint of the float of key k and the float of key k-1; d from the
//                     float format's inverse (d = t, 1/t, f n/(f(1-t) + t n), n f/(t(f-n) + n), n/t)
//   OpenGL (_gl)      t = the midpoint of a_k, the first float z_ndc (in depth order) whose
//                     window depth stores key k or later, and the z_ndc float before it; d from
//                     z_ndc: 2fn/(f(1-t) + n(1+t)) (reversed: 2fn/(f(1+t) + n(1-t)))
// For the formats with a common denominator, d = K/D(t) with D linear in t, so
// d(t2) - d(t1) = K (D(t1) - D(t2))/(D(t1) D(t2)), and D(t1) - D(t2) is (t1 - t2) times D's slope:
// nothing nearly equal is subtracted.
enum class Family { unorm, unormReversed, log, int31, uint32, uint32plus1, floatUp, floatDown, gl };

Family familyOf(DepthFormat f) {
    switch (f) {
    case DepthFormat::unorm16:
    case DepthFormat::unorm24:
    case DepthFormat::depth24plus: return Family::unorm;
    case DepthFormat::unorm16_reversed:
    case DepthFormat::unorm24_reversed: return Family::unormReversed;
    case DepthFormat::log24: return Family::log;
    case DepthFormat::int31_inv: return Family::int31;
    case DepthFormat::uint32_inv: return Family::uint32;
    case DepthFormat::uint32_inv1: return Family::uint32plus1;
    case DepthFormat::linear_f32:
    case DepthFormat::f32:
    case DepthFormat::depth32float: return Family::floatUp;
    case DepthFormat::inv_f32:
    case DepthFormat::f32_reversed:
    case DepthFormat::f32_reversed_inf: return Family::floatDown;
    case DepthFormat::unorm24_gl:
    case DepthFormat::f32_gl:
    case DepthFormat::f32_gl_reversed: return Family::gl;
    }
    return Family::floatUp;
}

// Floats in a total order: ord(x) < ord(y) <=> x < y (-0 just below +0); bijective on bit patterns.
uint32_t floatOrd(float x) {
    const uint32_t u = floatBits(x);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
float floatFromOrd(uint32_t o) { return floatFromBits((o & 0x80000000u) ? (o & 0x7FFFFFFFu) : ~o); }

struct KeySegment {
    uint64_t first = 0, last = 0;  // keys first, first + stride, ..., <= last
    uint64_t stride = 1;
    // OpenGL formats where consecutive z_ndc floats store values more than one key apart (the
    // window depth is exact and its floats are denser): first..last are atoms (depth-order ords),
    // one bucket each.
    bool atoms = false;
};

struct BucketModel {
    DepthEncoder e;
    Family family = Family::floatUp;
    double lo = 0, hi = 0;          // the search range [lo, hi]
    uint64_t kFirst = 0, kLast = 0; // keys of lo and hi
    // OpenGL formats: z_ndc floats ("atoms") in depth order as ords: atomOrd(z) = floatOrd(z)
    // (standard: z_ndc grows with depth) or ~floatOrd(z) (reversed); atoms of lo and hi.
    bool glReversed = false;
    uint32_t atomFirst = 0, atomLast = 0;

    float atomAt(uint32_t o) const { return floatFromOrd(glReversed ? ~o : o); }
    uint32_t atomOrd(float z) const { return glReversed ? ~floatOrd(z) : floatOrd(z); }
    // The encoder's key of a z_ndc float (render/depth_format_impl.h, from z_ndc on).
    uint32_t keyOfAtom(float zndc) const {
        const float w = zndc * 0.5f + 0.5f;
        if (e.format == DepthFormat::f32_gl) return floatBits(w);
        if (e.format == DepthFormat::f32_gl_reversed) return ~floatBits(w);
        double v = std::nearbyint(16777215.0 * double(w));
        v = v < 0 ? 0 : (v > 16777215.0 ? 16777215.0 : v);
        return uint32_t(v);
    }
    // The first atom (depth order, within [atomFirst, atomLast]) whose key is >= k (k <= kLast).
    // The key is non-decreasing in the atom (each rounding is monotone): bisection.
    uint32_t firstAtomOfKey(uint64_t k) const {
        uint32_t a = atomFirst, b = atomLast;  // key(b) >= k
        while (a < b) {
            const uint32_t m = a + (b - a) / 2;
            if (keyOfAtom(atomAt(m)) >= k) b = m;
            else a = m + 1;
        }
        return a;
    }

    // The threshold value of key k (kFirst < k <= kLast).
    double threshold(uint64_t k) const {
        const double S = unormScale(e.format);
        switch (family) {
        case Family::unorm:
        case Family::log: return double(k) - 0.5;
        case Family::unormReversed: return S - double(k) + 0.5;
        case Family::int31: return kC31 - double(k) + 1;
        case Family::uint32:
        case Family::uint32plus1: return 4294967296.0 - double(k);
        case Family::floatUp:
            return 0.5 * (double(floatFromBits(uint32_t(k))) + double(floatFromBits(uint32_t(k - 1))));
        case Family::floatDown:
            return 0.5 * (double(floatFromBits(~uint32_t(k))) + double(floatFromBits(~uint32_t(k - 1))));
        case Family::gl: {
            const uint32_t a = firstAtomOfKey(k);
            return 0.5 * (double(atomAt(a)) + double(atomAt(a - 1)));  // a > atomFirst: k > kFirst
        }
        }
        return NAN;
    }

    // The common denominator D(t) of the formats written d = K/D(t), stable where it is small.
    double denominator(double t) const {
        const double n = e.nearZ, f = e.farZ, S = unormScale(e.format);
        switch (e.format) {
        case DepthFormat::unorm16:
        case DepthFormat::unorm24:
        case DepthFormat::depth24plus: return f * ((S - t) / S) + (t / S) * n;
        case DepthFormat::unorm16_reversed:
        case DepthFormat::unorm24_reversed: return (t / S) * (f - n) + n;
        case DepthFormat::f32:
        case DepthFormat::depth32float: return f * (1.0 - t) + t * n;
        case DepthFormat::f32_reversed: return t * (f - n) + n;
        case DepthFormat::unorm24_gl:
        case DepthFormat::f32_gl: return f * (1.0 - t) + n * (1.0 + t);
        case DepthFormat::f32_gl_reversed: return f * (1.0 + t) + n * (1.0 - t);
        default: return t;  // K/t: inv_f32, f32_reversed_inf, the integer 1/d formats
        }
    }
    // K of d = K/D(t) and the slope factor c with D(t1) - D(t2) = c (t2 - t1).
    void constants(double *K, double *c) const {
        const double n = e.nearZ, f = e.farZ, S = unormScale(e.format);
        switch (e.format) {
        case DepthFormat::unorm16:
        case DepthFormat::unorm24:
        case DepthFormat::depth24plus: *K = f * n, *c = (f - n) / S; return;
        case DepthFormat::unorm16_reversed:
        case DepthFormat::unorm24_reversed: *K = n * f, *c = -(f - n) / S; return;
        case DepthFormat::f32:
        case DepthFormat::depth32float: *K = f * n, *c = f - n; return;
        case DepthFormat::f32_reversed: *K = n * f, *c = -(f - n); return;
        case DepthFormat::unorm24_gl:
        case DepthFormat::f32_gl: *K = 2 * f * n, *c = f - n; return;
        case DepthFormat::f32_gl_reversed: *K = 2 * f * n, *c = -(f - n); return;
        case DepthFormat::inv_f32: *K = 1, *c = -1; return;
        case DepthFormat::f32_reversed_inf: *K = n, *c = -1; return;
        case DepthFormat::int31_inv: *K = kC31, *c = -1; return;
        default: *K = kC32, *c = -1; return;  // uint32_inv, uint32_inv1
        }
    }

    double depthAt(double t) const {
        switch (family) {
        case Family::log: return std::expm1(e.logDenominator * t / unormScale(e.format)) / e.logC;
        case Family::floatUp:
            if (e.format == DepthFormat::linear_f32) return t;
            break;
        case Family::uint32plus1: return kC32 / t - 1.0;
        default: break;
        }
        double K, c;
        constants(&K, &c);
        return K / denominator(t);
    }
    // depthAt(t2) - depthAt(t1), without cancellation.
    double widthBetween(double t1, double t2) const {
        if (family == Family::log) {
            const double S = unormScale(e.format), L = e.logDenominator;
            return std::exp(L * t1 / S) * std::expm1(L * (t2 - t1) / S) / e.logC;
        }
        if (e.format == DepthFormat::linear_f32) return t2 - t1;
        double K, c;
        constants(&K, &c);
        return K * (c * (t2 - t1)) / (denominator(t1) * denominator(t2));
    }

    // Where key k's bucket starts and its width, both cut to [lo, hi].
    double bucketStart(uint64_t k) const { return k == kFirst ? lo : std::max(lo, depthAt(threshold(k))); }
    double bucketWidth(uint64_t k) const {
        if (k == kFirst || k == kLast) {
            const double a = bucketStart(k);
            const double b = k == kLast ? hi : std::min(hi, depthAt(threshold(k + 1)));
            return b - a;
        }
        return widthBetween(threshold(k), threshold(k + 1));
    }
    // The bucket of a single atom o (a z_ndc float that alone stores its key, strictly between the
    // keys of lo and hi): between the thresholds half-way to its neighbours in depth order.
    double atomThreshold(uint32_t o) const { return 0.5 * (double(atomAt(o)) + double(atomAt(o - 1))); }
    double atomBucketStart(uint32_t o) const { return depthAt(atomThreshold(o)); }
    double atomBucketWidth(uint32_t o) const { return widthBetween(atomThreshold(o), atomThreshold(o + 1)); }
};

BucketModel makeBucketModel(const DepthEncoder &e, double lo, double hi) {
    BucketModel m;
    m.e = e;
    m.family = familyOf(e.format);
    m.lo = lo;
    m.hi = hi;
    m.kFirst = depthKey(e, lo);
    m.kLast = depthKey(e, hi);
    if (m.family == Family::gl) {
        // The encoder's z_ndc at lo and hi (render/depth_format_impl.h: one rounding to float).
        const double n = e.nearZ, f = e.farZ;
        m.glReversed = e.format == DepthFormat::f32_gl_reversed;
        auto zndc = [&](double d) {
            return m.glReversed ? float((2 * f * n) / ((f - n) * d) - (f + n) / (f - n))
                                : float((f + n) / (f - n) - (2 * f * n) / ((f - n) * d));
        };
        m.atomFirst = m.atomOrd(zndc(lo));
        m.atomLast = m.atomOrd(zndc(hi));
    }
    return m;
}

// The key runs over [kFirst, kLast] along which bucket widths do not decrease (with the buckets of
// kFirst and kLast, cut by the range, alone), in depth order of their first key:
//   - one run for the formats whose widths grow with depth everywhere: unorm*, log24, the integer
//     1/d formats (thresholds equally spaced in t, d(t) convex), linear_f32 and f32 (float spacing
//     non-decreasing in t as d grows, d(t) convex);
//   - the floats that shrink with depth (inv_f32, f32_reversed, f32_reversed_inf): one run per
//     binade interior (2^e, 2^(e+1)), where the spacing is constant, and the power of two 2^e
//     alone (its bucket spans half a spacing above and a quarter below: narrower than both
//     neighbours' runs allow);
//   - the OpenGL formats: per z_ndc binade (constant float spacing; atom widths grow with depth,
//     d(z_ndc) convex), the keys all of whose atoms lie inside it, as two runs of every other key:
//     the window depth w = fl(z_ndc/2 + 1/2) takes 2^i + 1 and 2^i - 1 atoms in turn (ties go to
//     the even w), and 24-bit rounding maps w one to one in [0.5, 1) and two w to a value below
//     0.5, so every other key holds the same number of atoms, each wider than the last; the keys
//     at a binade's ends, alone.
std::vector<KeySegment> monotoneRuns(const BucketModel &m) {
    std::vector<KeySegment> runs;
    auto single = [&](uint64_t k) {
        if (k >= m.kFirst && k <= m.kLast) runs.push_back({k, k, 1});
    };
    // A run [a, b] inside (kFirst, kLast) with a stride.
    auto run = [&](uint64_t a, uint64_t b, uint64_t stride) {
        a = std::max(a, m.kFirst + 1);
        if (m.kLast == 0) return;
        b = std::min(b, m.kLast - 1);
        if (a <= b) runs.push_back({a, b, stride});
    };
    single(m.kFirst);
    if (m.kLast > m.kFirst) single(m.kLast);
    switch (m.family) {
    case Family::floatDown: {
        // Keys ~bits: walk the stored floats from the float of kFirst down to the float of kLast.
        uint32_t bits = ~uint32_t(m.kFirst);
        const uint32_t lastBits = ~uint32_t(m.kLast);
        while (true) {
            const uint32_t binade = bits & 0xFF800000u;  // sign and exponent: the power of two
            if ((bits & 0x007FFFFFu) != 0) run(~uint64_t(bits) & 0xFFFFFFFFu, ~uint64_t(binade | 1u) & 0xFFFFFFFFu, 1);
            single(~uint64_t(binade) & 0xFFFFFFFFu);
            if (binade <= lastBits || binade == 0) break;
            bits = binade - 1;
        }
        break;
    }
    case Family::gl: {
        for (uint32_t o = m.atomFirst;;) {
            // The binade of atom o: same sign and exponent field; its last atom in depth order.
            const uint32_t u = floatBits(m.atomAt(o));
            const uint32_t oa = m.atomOrd(floatFromBits(u & 0xFF800000u)),
                           ob = m.atomOrd(floatFromBits(u | 0x007FFFFFu));
            const uint32_t end = std::min(std::max(oa, ob), m.atomLast);
            const uint64_t ka = m.keyOfAtom(m.atomAt(o)), kb = m.keyOfAtom(m.atomAt(end));
            single(ka);
            single(kb);
            if (kb - ka > uint64_t(end - o)) {
                // More keys than atoms: the window depth is exact here (w = (z_ndc + 1)/2 needs no
                // rounding) and its floats are denser, so every atom alone stores its key and the
                // keys in between are never stored: one run over the atoms, those of kFirst and
                // kLast (already alone) left out.
                uint32_t a = o, b = end;
                while (a <= b && m.keyOfAtom(m.atomAt(a)) <= m.kFirst) ++a;
                while (b >= a && m.keyOfAtom(m.atomAt(b)) >= m.kLast) --b;
                if (a <= b) runs.push_back({a, b, 1, true});
            } else if (kb > ka + 1) {
                run(ka + 1, kb - 1, 2);
                run(ka + 2, kb - 1, 2);
            }
            if (end >= m.atomLast) break;
            o = end + 1;
        }
        break;
    }
    default: run(m.kFirst + 1, m.kLast - 1, 1); break;
    }
    return runs;
}

std::optional<DepthBucketFound> firstWide(const BucketModel &m, double minWidth, bool orEqual) {
    auto isWide = [&](double w) { return orEqual ? w >= minWidth : w > minWidth; };
    // A run's i-th bucket: its start and width.
    auto startOf = [&](const KeySegment &r, uint64_t i) {
        const uint64_t x = r.first + i * r.stride;
        return r.atoms ? m.atomBucketStart(uint32_t(x)) : m.bucketStart(x);
    };
    auto widthOf = [&](const KeySegment &r, uint64_t i) {
        const uint64_t x = r.first + i * r.stride;
        return r.atoms ? m.atomBucketWidth(uint32_t(x)) : m.bucketWidth(x);
    };
    std::vector<KeySegment> runs = monotoneRuns(m);
    // In depth order of their first bucket, so that once a run starts at or beyond the best found,
    // so do all later ones.
    std::vector<std::pair<double, size_t>> order;
    for (size_t i = 0; i < runs.size(); ++i) order.emplace_back(startOf(runs[i], 0), i);
    std::sort(order.begin(), order.end());
    std::optional<DepthBucketFound> best;
    for (const auto &[start0, ri] : order) {
        if (best && start0 >= best->depth) break;
        const KeySegment &r = runs[ri];
        const uint64_t count = (r.last - r.first) / r.stride + 1;
        if (!isWide(widthOf(r, count - 1))) continue;  // the widest of the run: none is wide
        uint64_t a = 0, b = count - 1;                  // the first wide index is in [a, b]
        while (a < b) {
            const uint64_t mid = a + (b - a) / 2;
            if (isWide(widthOf(r, mid))) b = mid;
            else a = mid + 1;
        }
        const double start = startOf(r, a);
        const uint64_t x = r.first + a * r.stride;
        const uint32_t key = r.atoms ? m.keyOfAtom(m.atomAt(uint32_t(x))) : uint32_t(x);
        if (!best || start < best->depth) best = DepthBucketFound{start, key, widthOf(r, a)};
    }
    return best;
}

// near, every power of ten strictly between, far. Powers of ten are parsed from "1e<k>" so each is
// the correctly rounded double of 10^k on every platform.
std::vector<double> decadeDepths(double n, double f) {
    std::vector<double> v{n};
    const int k0 = int(std::floor(std::log10(n))) - 1, k1 = int(std::ceil(std::log10(f))) + 1;
    for (int k = k0; k <= k1; ++k) {
        const double p = std::stod("1e" + std::to_string(k));
        if (p > n && p < f) v.push_back(p);
    }
    v.push_back(f);
    return v;
}

std::string formatDouble(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

}  // namespace

// ---- Inverses ---------------------------------------------------------------------------------
// With s the stored value (z for the normalized float formats), C the integer numerator, S = 2^N-1:
//   linear_f32        d = s
//   inv_f32           d = 1/s
//   int31_inv         d = C31/(s + 1/2)      (s = floor(C/d): the center of [s, s+1))
//   uint32_inv        d = C32/(s + 1/2)
//   uint32_inv1       d = C32/(s + 1/2) - 1
//   unorm*, *_gl      z = s/S; solving z = f(d-n)/(d(f-n)) for d: d = f n / (f(1-z) + z n)
//                     = S f n / ((S - s) f + s n)  (the subtraction S - s is exact: integers)
//   unorm*_reversed   z = s/S; z = n(f-d)/(d(f-n)) gives d = n f / (z (f-n) + n)
//   f32, f32_gl       d = f n / (f (1 - z) + z n)   (1 - z is exact in double for a float z <= 1)
//   f32_reversed, f32_gl_reversed   z d (f-n) = n f - n d  =>  d = n f / (z (f-n) + n)
//   f32_reversed_inf  d = n / z
//   log24             ln(C d + 1) = L s/S  =>  d = expm1(L s/S) / C
// unorm24_gl's and f32_gl's window depth w = (z_ndc + 1)/2 equals f(d-n)/(d(f-n)) in real
// arithmetic (f32_gl_reversed's equals n(f-d)/(d(f-n))), so their inverses are unorm24's, f32's and
// f32_reversed's; the float steps on the way move values by less than half a step of the stored
// value, which the round-trip test checks. depth32float is f32, depth24plus is unorm24.
double depthFromStored(const DepthEncoder &e, double s) {
    const double n = e.nearZ, f = e.farZ, S = unormScale(e.format);
    switch (e.format) {
    case DepthFormat::linear_f32: return s;
    case DepthFormat::inv_f32: return 1.0 / s;
    case DepthFormat::int31_inv: return kC31 / (s + 0.5);
    case DepthFormat::uint32_inv: return kC32 / (s + 0.5);
    case DepthFormat::uint32_inv1: return kC32 / (s + 0.5) - 1.0;
    case DepthFormat::unorm16:
    case DepthFormat::unorm24:
    case DepthFormat::depth24plus:
    case DepthFormat::unorm24_gl: return f * n / (f * ((S - s) / S) + (s / S) * n);
    case DepthFormat::unorm16_reversed:
    case DepthFormat::unorm24_reversed: return n * f / ((s / S) * (f - n) + n);
    case DepthFormat::f32:
    case DepthFormat::depth32float:
    case DepthFormat::f32_gl: return f * n / (f * (1.0 - s) + s * n);
    case DepthFormat::f32_reversed:
    case DepthFormat::f32_gl_reversed: return n * f / (s * (f - n) + n);
    case DepthFormat::f32_reversed_inf: return n / s;
    case DepthFormat::log24: return std::expm1(e.logDenominator * s / S) / e.logC;
    }
    return NAN;
}

// d(b) - d(a) over a common denominator. With d = K / D(s) (K constant, D linear in s):
//   d(b) - d(a) = K (D(a) - D(b)) / (D(a) D(b)) = d(a) (D(a) - D(b)) / D(b),
// and D(a) - D(b) is (b - a) times D's slope, so no two nearly equal quantities are subtracted:
//   unorm*: D = f(S-s)/S + s n/S, D(a)-D(b) = (b-a)(f-n)/S     f32: D = f(1-z) + z n, (b-a)(f-n)
//   unorm*_reversed: D = (s/S)(f-n) + n, D(a)-D(b) = (a-b)(f-n)/S
//   f32_reversed: D = z(f-n) + n, D(a)-D(b) = (a-b)(f-n)       1/s, C/(s+1/2), n/s: (a-b)/b etc.
//   log24: (expm1(x_b) - expm1(x_a))/C = exp(x_a) expm1(x_b - x_a)/C with x = L s/S.
double depthBetweenStored(const DepthEncoder &e, double a, double b) {
    const double n = e.nearZ, f = e.farZ, S = unormScale(e.format);
    switch (e.format) {
    case DepthFormat::linear_f32: return b - a;  // two floats: exact in double
    case DepthFormat::inv_f32: return (a - b) / (a * b);
    case DepthFormat::int31_inv: return kC31 * (a - b) / ((a + 0.5) * (b + 0.5));
    case DepthFormat::uint32_inv:
    case DepthFormat::uint32_inv1: return kC32 * (a - b) / ((a + 0.5) * (b + 0.5));
    case DepthFormat::unorm16:
    case DepthFormat::unorm24:
    case DepthFormat::depth24plus:
    case DepthFormat::unorm24_gl: {
        const double Db = f * ((S - b) / S) + (b / S) * n;
        return depthFromStored(e, a) * ((b - a) / S) * (f - n) / Db;
    }
    case DepthFormat::unorm16_reversed:
    case DepthFormat::unorm24_reversed: {
        const double Db = (b / S) * (f - n) + n;
        return depthFromStored(e, a) * ((a - b) / S) * (f - n) / Db;
    }
    case DepthFormat::f32:
    case DepthFormat::depth32float:
    case DepthFormat::f32_gl: {
        const double Db = f * (1.0 - b) + b * n;
        return depthFromStored(e, a) * (b - a) * (f - n) / Db;
    }
    case DepthFormat::f32_reversed:
    case DepthFormat::f32_gl_reversed: {
        const double Db = b * (f - n) + n;
        return depthFromStored(e, a) * (a - b) * (f - n) / Db;
    }
    case DepthFormat::f32_reversed_inf: return n * (a - b) / (a * b);
    case DepthFormat::log24: {
        const double xa = e.logDenominator * a / S, xb = e.logDenominator * b / S;
        return std::exp(xa) * std::expm1(xb - xa) / e.logC;
    }
    }
    return NAN;
}

// Inverse of depthKeyFromStored: float formats keep the bit pattern (complemented when nearer is
// larger), int31_inv stores 2^31-1 - key, the 32-bit inverse formats the complement, the reversed
// unorms S - key, the other unorms the key.
double storedFromKey(const DepthEncoder &e, uint32_t key) {
    switch (e.format) {
    case DepthFormat::linear_f32:
    case DepthFormat::f32:
    case DepthFormat::f32_gl:
    case DepthFormat::depth32float: return floatFromBits(key);
    case DepthFormat::inv_f32:
    case DepthFormat::f32_reversed:
    case DepthFormat::f32_reversed_inf:
    case DepthFormat::f32_gl_reversed: return floatFromBits(~key);
    case DepthFormat::int31_inv: return double(2147483647 - int64_t(key));
    case DepthFormat::uint32_inv:
    case DepthFormat::uint32_inv1: return double(~key);
    case DepthFormat::unorm16_reversed:
    case DepthFormat::unorm24_reversed: return unormScale(e.format) - double(key);
    default: return double(key);
    }
}

bool depthFormatFights(const DepthEncoder &e, double d, double gap) { return depthKey(e, d + gap) <= depthKey(e, d); }

bool validateDepthAuditRange(double nearZ, double farZ, std::string *err) {
    auto fail = [&](const std::string &m) {
        if (err) *err = m;
        return false;
    };
    if (!std::isfinite(nearZ) || !(nearZ >= FLT_MIN))
        return fail("near plane " + formatDouble(nearZ) +
                    " must be a finite distance >= 1.2e-38 (the smallest normal float); use e.g. --near 0.1");
    if (!std::isfinite(farZ) || !(farZ > nearZ))
        return fail("far plane " + formatDouble(farZ) + " must be finite and greater than the near plane " +
                    formatDouble(nearZ) + "; use e.g. --far 1000");
    if (farZ > FLT_MAX)
        return fail("far plane " + formatDouble(farZ) +
                    " exceeds the largest float 3.4e38, so float formats cannot hold it; use a smaller --far");
    return true;
}

void depthRepresentableRange(const DepthEncoder &e, double *lo, double *hi, std::string *note) {
    const double nearZ = e.nearZ, farZ = e.farZ;
    *lo = std::max(nearZ, e.minValidDepth);
    *hi = farZ;
    std::string why;
    if (e.format == DepthFormat::int31_inv || e.format == DepthFormat::uint32_inv) {
        const char *c = e.format == DepthFormat::int31_inv ? "2^31-1" : "2^32-1";
        const double C = e.format == DepthFormat::int31_inv ? kC31 : kC32;
        if (nearZ < 1)
            why = std::string("depths below 1 cannot be stored: (") + c +
                  ")/d exceeds the integer's range, so they clamp to the value at d = 1";
        if (farZ > C) {
            *hi = C;
            if (!why.empty()) why += "; ";
            why += std::string("depths beyond ") + c + " all store 0";
        }
    } else if (e.format == DepthFormat::uint32_inv1 && farZ > kC32 - 1) {
        *hi = kC32 - 1;
        why = "depths beyond 2^32-2 all store 0";
    }
    if (note) *note = why;
}

std::optional<DepthBucket> depthBucketAt(const DepthEncoder &e, double d) {
    double lo, hi;
    depthRepresentableRange(e, &lo, &hi, nullptr);
    if (!(d >= lo && d <= hi)) return std::nullopt;
    const BucketModel m = makeBucketModel(e, lo, hi);
    const uint64_t k = depthKey(e, d);
    DepthBucket b;
    b.key = uint32_t(k);
    b.lo = m.bucketStart(k);
    b.width = m.bucketWidth(k);
    b.hi = k == m.kLast ? hi : std::min(hi, m.depthAt(m.threshold(k + 1)));
    return b;
}

std::optional<DepthBucketFound> firstBucketWiderThan(const DepthEncoder &e, double lo, double hi, double minWidth,
                                                     bool orEqual) {
    double rlo, rhi;
    depthRepresentableRange(e, &rlo, &rhi, nullptr);
    lo = std::max(lo, rlo);
    hi = std::min(hi, rhi);
    if (!(hi > lo) || !(minWidth >= 0)) return std::nullopt;
    return firstWide(makeBucketModel(e, lo, hi), minWidth, orEqual);
}

std::optional<DepthBucketFound> fightOnset(const DepthEncoder &e, double lo, double hi, double gap) {
    return firstBucketWiderThan(e, lo, hi, gap, false);
}

std::optional<DepthBucketFound> fightLikely(const DepthEncoder &e, double lo, double hi, double gap) {
    return firstBucketWiderThan(e, lo, hi, 2 * gap, true);
}

const std::vector<DepthFormat> &depthFormatsCheapestFirst() {
    using F = DepthFormat;
    static const std::vector<DepthFormat> order = {
        F::unorm16,       F::unorm16_reversed,                                        // 16 bits
        F::unorm24,       F::unorm24_reversed, F::unorm24_gl, F::depth24plus, F::log24,  // 24
        F::int31_inv,                                                                 // 31
        F::f32,           F::f32_reversed,     F::f32_reversed_inf, F::f32_gl, F::f32_gl_reversed,
        F::depth32float,  F::linear_f32,       F::inv_f32,          F::uint32_inv, F::uint32_inv1,  // 32
    };
    return order;
}

DepthAuditResult auditDepthFormats(double nearZ, double farZ, const std::vector<DepthFormat> &formats,
                                   const DepthAuditSettings &settings) {
    return auditDepthFormats(nearZ, farZ, std::vector<DepthFormatSpec>(formats.begin(), formats.end()), settings);
}

DepthAuditResult auditDepthFormats(double nearZ, double farZ, std::initializer_list<DepthFormat> formats,
                                   const DepthAuditSettings &settings) {
    return auditDepthFormats(nearZ, farZ, std::vector<DepthFormatSpec>(formats.begin(), formats.end()), settings);
}

DepthAuditResult auditDepthFormats(double nearZ, double farZ, const std::vector<DepthFormatSpec> &formats,
                                   const DepthAuditSettings &settings) {
    DepthAuditResult r;
    r.nearZ = nearZ;
    r.farZ = farZ;
    if (!validateDepthAuditRange(nearZ, farZ, &r.error)) return r;
    if (formats.empty()) {
        r.error = "no depth formats to audit; pass at least one, e.g. --formats f32,f32_reversed";
        return r;
    }
    for (size_t i = 0; i < formats.size(); ++i) {
        for (size_t j = 0; j < i; ++j)
            if (formats[i] == formats[j]) {
                r.error = "depth format '" + depthFormatName(formats[i]) + "' is listed twice; list it once";
                return r;
            }
        if (!validateDepthFormatRange(formats[i], nearZ, farZ, &r.error)) return r;
    }
    for (double g : settings.fightGaps)
        if (!std::isfinite(g) || !(g > 0)) {
            r.error = "fight gap " + formatDouble(g) + " must be a finite distance > 0, e.g. 0.01 (1 cm)";
            return r;
        }
    if (settings.curveSamples < 2) {
        r.error = "curveSamples must be at least 2";
        return r;
    }

    r.decadeDepths = decadeDepths(nearZ, farZ);
    r.fightGaps = settings.fightGaps;
    // Geometric bin centers: d_i = n (f/n)^((i + 1/2)/N), strictly inside (n, f).
    const double logRatio = std::log(farZ / nearZ);
    for (int i = 0; i < settings.curveSamples; ++i)
        r.curveDepths.push_back(nearZ * std::exp(logRatio * (double(i) + 0.5) / double(settings.curveSamples)));

    for (const DepthFormatSpec &fmt : formats) {
        const DepthEncoder e = makeDepthEncoder(fmt, nearZ, farZ);
        const DepthFormatInfo &info = depthFormatInfo(fmt.format);
        DepthFormatAudit a;
        a.format = fmt;
        a.name = depthFormatName(fmt);
        a.bits = info.bits;
        a.nearerIsLarger = info.nearerIsLarger;

        // Distinct values: keys are ordered and equal exactly for equal stored values, and every
        // key between two produced keys is a value of the format (an integer in range, or a float
        // bit pattern between the two), so the count is the key difference + 1. Depths below the
        // format's minimum clamp to its value, so key(near) is the clamped one.
        a.distinctValues = uint64_t(depthKey(e, farZ)) - uint64_t(depthKey(e, nearZ)) + 1;

        // Representable part of [near, far].
        depthRepresentableRange(e, &a.representableNear, &a.representableFar, &a.rangeNote);

        for (double d : r.decadeDepths) a.decades.push_back(resolutionAt(e, d));
        // Fight distances: over the representable range up to far (the pair must fit before far:
        // a bucket's width counts up to far).
        const double hi = std::min(a.representableFar, farZ);
        for (double g : r.fightGaps) {
            DepthFightDistance fd;
            fd.gap = g;
            if (const auto on = fightOnset(e, a.representableNear, hi, g)) {
                fd.onset = on->depth;
                fd.onsetBucket = on->width;
            }
            if (const auto lk = fightLikely(e, a.representableNear, hi, g)) fd.likely = lk->depth;
            a.fights.push_back(fd);
        }
        for (double d : r.curveDepths) a.curveResolution.push_back(resolutionAt(e, d).resolution);
        r.formats.push_back(std::move(a));
    }
    return r;
}

}  // namespace va
