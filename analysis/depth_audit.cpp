// View-independent depth-format audit: resolution, distinct values, fight distances, range.
// Every number is measured by calling the format's own encoder (render/depth_format.h); the
// closed forms are computed alongside only to compare. Derivations: docs/depth-formats.md.
#include "analysis/depth_audit.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <string>

#include "render/depth_format_impl.h"

namespace va {

namespace {

constexpr double kC31 = 2147483647.0;  // 2^31 - 1, int31_inv's numerator
constexpr double kC32 = 4294967295.0;  // 2^32 - 1, uint32_inv's and uint32_inv1's numerator

// The unorm scale S = 2^N - 1 of the integer-normalized formats (0 for the others).
double unormScale(DepthFormat f) {
    switch (f) {
    case DepthFormat::unorm16: return 65535.0;
    case DepthFormat::unorm24:
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
    case DepthFormat::log24: return true;
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
//   f32               ulp(z) d^2 (f-n) / (f n)
//   f32_reversed      z = n(f-d)/(d(f-n)), |dz/dd| = nf/((f-n)d^2): ulp(z) d^2 (f-n) / (n f)
//   f32_reversed_inf  z = n/d: ulp(z) d^2 / n
//   log24             s/S = ln(Cd+1)/L, ds/dd = S C/(L(Cd+1)):  L (C d + 1) / (S C)
double closedFormResolution(const DepthEncoder &e, double d, double stored, bool towardsFar) {
    const double n = e.nearZ, f = e.farZ, S = unormScale(e.format);
    // Towards far a float's stored value grows when nearer is smaller (linear_f32, f32) and shrinks
    // when nearer is larger (inv_f32, f32_reversed, f32_reversed_inf).
    const bool up = towardsFar != depthFormatInfo(e.format).nearerIsLarger;
    auto floatUlp = [up](double x) { return floatSpacing(x, up); };
    switch (e.format) {
    case DepthFormat::linear_f32: return floatUlp(d);
    case DepthFormat::inv_f32: return d * d * floatUlp(stored);
    case DepthFormat::int31_inv: return d * d / kC31;
    case DepthFormat::uint32_inv: return d * d / kC32;
    case DepthFormat::uint32_inv1: return (d + 1) * (d + 1) / kC32;
    case DepthFormat::unorm16:
    case DepthFormat::unorm24:
    case DepthFormat::unorm24_gl: return d * (d / n) * ((f - n) / f) / S;
    case DepthFormat::f32: return floatUlp(stored) * d * (d / n) * ((f - n) / f);
    case DepthFormat::f32_reversed: return floatUlp(stored) * d * (d / n) * ((f - n) / f);
    case DepthFormat::f32_reversed_inf: return floatUlp(stored) * d * (d / n);
    case DepthFormat::log24: return e.logDenominator * (kLogDepthC * d + 1) / (S * kLogDepthC);
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

// The fight distance for one gap over [lo, hi] = [representable near, far - gap]:
//   1. coarse scan: N log-spaced depths d_i = lo (hi/lo)^(i/(N-1)), d_0 = lo, d_{N-1} = hi;
//   2. the first d_i that fights; if i = 0 the answer is lo;
//   3. otherwise bisect over the doubles of (d_{i-1}, d_i] for the first fighting one.
// The predicate is not monotone near the onset (two surfaces a gap apart share a bucket only when
// the bucket is wider than the gap *and* they fall inside the same one, which depends on where the
// bucket boundaries lie), so this is the first *sampled* onset refined by bisection: a fight at an
// isolated depth between two samples that both do not fight can be missed, by design.
std::optional<double> fightDistance(const DepthEncoder &e, double lo, double hi, double gap, int samples) {
    if (!(hi >= lo)) return std::nullopt;
    const int N = hi > lo ? std::max(samples, 2) : 1;
    const double logRatio = std::log(hi / lo);
    double prev = lo;
    for (int i = 0; i < N; ++i) {
        const double di = i == 0 ? lo : (i == N - 1 ? hi : lo * std::exp(logRatio * double(i) / double(N - 1)));
        if (depthFormatFights(e, di, gap)) {
            if (i == 0) return lo;
            uint64_t a = doubleBits(prev), b = doubleBits(di);  // fights(a) false, fights(b) true
            while (b - a > 1) {
                const uint64_t m = a + (b - a) / 2;
                if (depthFormatFights(e, doubleFromBits(m), gap)) b = m;
                else a = m;
            }
            return doubleFromBits(b);
        }
        prev = di;
    }
    return std::nullopt;
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
//   f32               d = f n / (f (1 - z) + z n)   (1 - z is exact in double for a float z <= 1)
//   f32_reversed      z d (f-n) = n f - n d  =>  d = n f / (z (f-n) + n)
//   f32_reversed_inf  d = n / z
//   log24             ln(C d + 1) = L s/S  =>  d = expm1(L s/S) / C
// unorm24_gl's window depth w = (z_ndc + 1)/2 equals f(d-n)/(d(f-n)) in real arithmetic, so its
// inverse is unorm24's; its float steps on the way move values by less than half a 24-bit step,
// which the round-trip test checks.
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
    case DepthFormat::unorm24_gl: return f * n / (f * ((S - s) / S) + (s / S) * n);
    case DepthFormat::f32: return f * n / (f * (1.0 - s) + s * n);
    case DepthFormat::f32_reversed: return n * f / (s * (f - n) + n);
    case DepthFormat::f32_reversed_inf: return n / s;
    case DepthFormat::log24: return std::expm1(e.logDenominator * s / S) / kLogDepthC;
    }
    return NAN;
}

// d(b) - d(a) over a common denominator. With d = K / D(s) (K constant, D linear in s):
//   d(b) - d(a) = K (D(a) - D(b)) / (D(a) D(b)) = d(a) (D(a) - D(b)) / D(b),
// and D(a) - D(b) is (b - a) times D's slope, so no two nearly equal quantities are subtracted:
//   unorm*: D = f(S-s)/S + s n/S, D(a)-D(b) = (b-a)(f-n)/S     f32: D = f(1-z) + z n, (b-a)(f-n)
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
    case DepthFormat::unorm24_gl: {
        const double Db = f * ((S - b) / S) + (b / S) * n;
        return depthFromStored(e, a) * ((b - a) / S) * (f - n) / Db;
    }
    case DepthFormat::f32: {
        const double Db = f * (1.0 - b) + b * n;
        return depthFromStored(e, a) * (b - a) * (f - n) / Db;
    }
    case DepthFormat::f32_reversed: {
        const double Db = b * (f - n) + n;
        return depthFromStored(e, a) * (a - b) * (f - n) / Db;
    }
    case DepthFormat::f32_reversed_inf: return n * (a - b) / (a * b);
    case DepthFormat::log24: {
        const double xa = e.logDenominator * a / S, xb = e.logDenominator * b / S;
        return std::exp(xa) * std::expm1(xb - xa) / kLogDepthC;
    }
    }
    return NAN;
}

// Inverse of depthKeyFromStored: float formats keep the bit pattern (complemented when nearer is
// larger), int31_inv stores 2^31-1 - key, the 32-bit inverse formats the complement, unorms the key.
double storedFromKey(const DepthEncoder &e, uint32_t key) {
    switch (e.format) {
    case DepthFormat::linear_f32:
    case DepthFormat::f32: return floatFromBits(key);
    case DepthFormat::inv_f32:
    case DepthFormat::f32_reversed:
    case DepthFormat::f32_reversed_inf: return floatFromBits(~key);
    case DepthFormat::int31_inv: return double(2147483647 - int64_t(key));
    case DepthFormat::uint32_inv:
    case DepthFormat::uint32_inv1: return double(~key);
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

DepthAuditResult auditDepthFormats(double nearZ, double farZ, const std::vector<DepthFormat> &formats,
                                   const DepthAuditSettings &settings) {
    DepthAuditResult r;
    r.nearZ = nearZ;
    r.farZ = farZ;
    if (!validateDepthAuditRange(nearZ, farZ, &r.error)) return r;
    if (formats.empty()) {
        r.error = "no depth formats to audit; pass at least one, e.g. --formats f32,f32_reversed";
        return r;
    }
    std::set<DepthFormat> seen;
    for (DepthFormat f : formats)
        if (!seen.insert(f).second) {
            r.error = std::string("depth format '") + depthFormatInfo(f).name + "' is listed twice; list it once";
            return r;
        }
    for (double g : settings.fightGaps)
        if (!std::isfinite(g) || !(g > 0)) {
            r.error = "fight gap " + formatDouble(g) + " must be a finite distance > 0, e.g. 0.01 (1 cm)";
            return r;
        }
    if (settings.curveSamples < 2 || settings.fightScanSamples < 2) {
        r.error = "curveSamples and fightScanSamples must be at least 2";
        return r;
    }

    r.decadeDepths = decadeDepths(nearZ, farZ);
    r.fightGaps = settings.fightGaps;
    // Geometric bin centers: d_i = n (f/n)^((i + 1/2)/N), strictly inside (n, f).
    const double logRatio = std::log(farZ / nearZ);
    for (int i = 0; i < settings.curveSamples; ++i)
        r.curveDepths.push_back(nearZ * std::exp(logRatio * (double(i) + 0.5) / double(settings.curveSamples)));

    for (DepthFormat fmt : formats) {
        const DepthEncoder e = makeDepthEncoder(fmt, nearZ, farZ);
        const DepthFormatInfo &info = depthFormatInfo(fmt);
        DepthFormatAudit a;
        a.format = fmt;
        a.name = info.name;
        a.bits = info.bits;
        a.nearerIsLarger = info.nearerIsLarger;

        // Distinct values: keys are ordered and equal exactly for equal stored values, and every
        // key between two produced keys is a value of the format (an integer in range, or a float
        // bit pattern between the two), so the count is the key difference + 1. Depths below the
        // format's minimum clamp to its value, so key(near) is the clamped one.
        a.distinctValues = uint64_t(depthKey(e, farZ)) - uint64_t(depthKey(e, nearZ)) + 1;

        // Representable part of [near, far].
        a.representableNear = std::max(nearZ, e.minValidDepth);
        a.representableFar = farZ;
        if (fmt == DepthFormat::int31_inv || fmt == DepthFormat::uint32_inv) {
            const char *c = fmt == DepthFormat::int31_inv ? "2^31-1" : "2^32-1";
            const double C = fmt == DepthFormat::int31_inv ? kC31 : kC32;
            if (nearZ < 1)
                a.rangeNote = std::string("depths below 1 cannot be stored: (") + c +
                              ")/d exceeds the integer's range, so they clamp to the value at d = 1";
            if (farZ > C) {
                a.representableFar = C;
                if (!a.rangeNote.empty()) a.rangeNote += "; ";
                a.rangeNote += std::string("depths beyond ") + c + " all store 0";
            }
        } else if (fmt == DepthFormat::uint32_inv1 && farZ > kC32 - 1) {
            a.representableFar = kC32 - 1;
            a.rangeNote = "depths beyond 2^32-2 all store 0";
        }

        for (double d : r.decadeDepths) a.decades.push_back(resolutionAt(e, d));
        for (double g : r.fightGaps)
            a.fights.push_back({g, fightDistance(e, a.representableNear, std::min(a.representableFar, farZ - g), g,
                                                 settings.fightScanSamples)});
        for (double d : r.curveDepths) a.curveResolution.push_back(resolutionAt(e, d).resolution);
        r.formats.push_back(std::move(a));
    }
    return r;
}

}  // namespace va
