// View-independent depth-format audit (docs/depth-formats.md, Audits: "Depth formats"; docs/depth-formats.md).
//
// For a near/far pair and a list of formats, measures from each format's own arithmetic
// (render/depth_format.h: depthKey / depthStoredValue, exactly what the z-buffer stores):
//   - the world-space depth resolution at the decade distances near, 10^k (near < 10^k < far), far,
//     next to the closed form (derivative of the mapping times the stored value's spacing);
//   - a dense resolution curve (for the log-log plot, reports/depth_plot.h);
//   - the number of distinct stored values over [near, far];
//   - per surface gap (1 cm, 1 mm) the fight *onset*: the smallest depth at which a stored value's
//     bucket (the interval of depths that store it) is wider than the gap, so two surfaces the gap
//     apart can share a stored value; and the *likely* distance, from where a bucket is at least
//     twice the gap wide (a random pair the gap apart shares a value with probability >= 50%).
//     Both exact: searched over the format's bucket structure (the exact inverse of its stored
//     value), not sampled; docs/depth-formats.md says how for the formats whose buckets are not
//     monotone in depth;
//   - the part of [near, far] the format can represent at all.
//
// Usage (the `visaudit depth-audit` command):
//     std::string err;
//     if (!validateDepthAuditRange(n, f, &err)) { print err; exit 2; }
//     DepthAuditResult r = auditDepthFormats(n, f, allDepthFormats());
//     if (!r.error.empty()) { print r.error; exit 2; }
//     depthAuditTable(r); depthAuditJson(r); writeDepthResolutionPlot(r, path, &err);
//
// Units: world units, meters by convention (1 cm = 0.01). Depth d is view depth (> 0).
#pragma once

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "render/depth_format.h"

namespace va {

// ---- Per-format exact arithmetic the audit builds on ------------------------------------------

// The exact inverse of a format's mapping: the representative view depth of stored value `stored`
// (a value the format can hold, as depthStoredValue returns it). For rounding formats (unorm*,
// log24, every float format) it is the depth whose exact real-number image is `stored` itself (the
// center of the stored value's rounding interval); for truncating formats (int31_inv, uint32_inv,
// uint32_inv1) it is the depth whose image is stored + 0.5 (the center of [v, v + 1)). The
// formulas are in docs/depth-formats.md. Round trip: depthStoredValue(e, depthFromStored(e, v)) == v
// for every stored value a double depth produces (tests/test_depth_audit.cpp checks it); values
// no double depth reaches (floats just above 0 in f32) have an inverse but no round trip.
double depthFromStored(const DepthEncoder &e, double stored);

// depthFromStored(e, b) - depthFromStored(e, a), computed without cancellation (the difference
// of the two inverses written over a common denominator), so a step of 1e-12 m at 1e4 m is exact
// to a few ulps rather than lost in the subtraction of two nearly equal depths.
double depthBetweenStored(const DepthEncoder &e, double a, double b);

// The stored value of an ordering key (inverse of depthKeyFromStored).
double storedFromKey(const DepthEncoder &e, uint32_t key);

// True when surfaces at depths d and d + gap (gap > 0) are no longer ordered by the format: the
// farther one's key is not larger (equal stored values, or swapped). The z-fighting predicate.
bool depthFormatFights(const DepthEncoder &e, double d, double gap);

// ---- Buckets ----------------------------------------------------------------------------------
// A stored value's *bucket* is the interval of view depths that store it. Its ends are the depths
// at which the format's exact real-number mapping crosses a rounding threshold (half-way between
// two stored values for rounding formats, an integer for truncating ones, the threshold of the
// first float of the intermediate z_ndc for the OpenGL formats), mapped back through the exact
// inverse; docs/depth-formats.md lists them. The encoder's double arithmetic moves an end by a few
// ulps of the mapping (a relative 1e-9 of the bucket's width or less, tests/test_depth_audit.cpp).

// The part of [near, far] the encoder represents: [lo, hi]; *note (may be null) says why a part is
// not (empty when all of it is).
void depthRepresentableRange(const DepthEncoder &e, double *lo, double *hi, std::string *note);

struct DepthBucket {
    uint32_t key = 0;      // ordering key of the stored value
    double lo = 0, hi = 0; // the bucket's depths, cut to the representable range
    double width = 0;      // hi - lo, computed without cancellation (inside the range)
};
// The bucket of depth d (the encoder's key of d); nullopt when d is outside the representable range.
std::optional<DepthBucket> depthBucketAt(const DepthEncoder &e, double d);

struct DepthBucketFound {
    double depth = 0;      // where the bucket starts (cut to the search range's start)
    uint32_t key = 0;      // its ordering key
    double width = 0;      // its width, cut to the search range
};
// The first bucket in depth order over [lo, hi] (inside the representable range) whose width, cut
// to [lo, hi], is > minWidth (orEqual: >= minWidth). nullopt when no bucket is. Exact: every
// bucket is either proved narrower by a monotone bound (bisection over the keys of runs whose
// widths are monotone) or measured; up to buckets whose width equals minWidth to about 15
// significant digits, which the double arithmetic may count either way.
std::optional<DepthBucketFound> firstBucketWiderThan(const DepthEncoder &e, double lo, double hi, double minWidth,
                                                     bool orEqual = false);

// The fight onset for surfaces `gap` apart over [lo, hi]: the first bucket wider than gap (two
// surfaces at its start and gap behind share its stored value); the likely distance: the first
// bucket at least 2 * gap wide (a pair gap apart at a random place in it shares the value with
// probability (width - gap)/width >= 1/2). nullopt: none up to hi.
std::optional<DepthBucketFound> fightOnset(const DepthEncoder &e, double lo, double hi, double gap);
std::optional<DepthBucketFound> fightLikely(const DepthEncoder &e, double lo, double hi, double gap);

// ---- Result ------------------------------------------------------------------------------------

// Resolution of one format at one depth. Steps are world-space depth distances (meters, > 0);
// "absent" (std::nullopt, JSON null) where the step does not exist. Best values: small.
struct DepthResolutionSample {
    double depth = 0;            // d, the view depth sampled
    bool inRange = true;         // false: d is outside what the format can represent (int31_inv and
                                 // uint32_inv below d = 1); the steps below are then absent
    double stored = 0;           // the stored value at d (as depthStoredValue: float or integer)
    uint32_t key = 0;            // its ordering key (smaller = nearer)
    // Distance from d's stored value to the next distinct stored value towards far, both taken at
    // their representative depths (depthFromStored): depthFromStored(next) - depthFromStored(v).
    // "Next" is the stored value of the first double depth beyond d's bucket (found by bisecting
    // the encoder), so it is a value the format really produces. Absent at the format's last value
    // (d = far in formats that clamp at far).
    std::optional<double> stepToNext;
    // The same towards near: depthFromStored(v) - depthFromStored(previous). Absent at the first.
    std::optional<double> stepToPrev;
    // The resolution reported: stepToNext, or stepToPrev where there is no next value. Best: small.
    std::optional<double> resolution;
    // True when the neighbor behind `resolution` is more than one key away: the format holds values
    // in between that are never produced (f32 just above z = 0 at near, f32_reversed just above 0
    // at far: floats there are denser than the doubles d; f32_gl and f32_gl_reversed where the
    // window depth's floats are denser than the float z_ndc before it), so the step is that
    // input's spacing, not the stored float's. closedForm is then smaller (except for the OpenGL
    // formats, whose closed form takes z_ndc's spacing).
    bool skipsValues = false;
    // Width of the interval of double depths that store exactly d's value, measured by bisecting
    // the encoder for both ends (the clamped first/last buckets are cut at near/far, so at near and
    // far of clamping formats this is about half the step). A cross-check of `resolution`.
    std::optional<double> bucketWidth;
    // The closed-form resolution: |d depth / d stored| at d times the stored spacing there (1 for
    // integers, the float's ulp for floats); docs/depth-formats.md lists it per format.
    std::optional<double> closedForm;
    // resolution / closedForm - 1: how far the linearized closed form is from the measured step
    // (0 is perfect agreement; float formats differ by up to -0.5 at powers of two, where the
    // spacing towards far halves).
    std::optional<double> relativeDifference;
};

// The fight distances for one gap (m). Best: absent, or large.
struct DepthFightDistance {
    double gap = 0;                  // distance between the two surfaces (m), e.g. 0.01 or 0.001
    // The onset: the smallest depth at which a stored value's bucket is wider than the gap, so two
    // surfaces the gap apart can share a stored value (fightOnset). Absent ("never") when no bucket
    // of the representable part of [near, far] is.
    std::optional<double> onset;
    std::optional<double> onsetBucket;  // that bucket's width (m, > gap)
    // The likely distance: the smallest depth at which a bucket is at least 2 x gap wide; a random
    // pair of surfaces the gap apart there shares a stored value with probability >= 50%
    // (fightLikely). Absent: never.
    std::optional<double> likely;
};

struct DepthFormatAudit {
    DepthFormatSpec format;          // the format (log24's C included)
    std::string name;                // format name as docs/depth-formats.md and --formats spell it (log24:C=X)
    int bits = 0;                    // bits of the stored value
    bool nearerIsLarger = false;     // comparison direction of the stored value
    // Distinct stored values over [near, far] (exact, from the ordering keys: key(far) - key(near)
    // + 1; for floats that is the count of representable floats between the two stored values,
    // inclusive; a format clamping below near's depth counts from its clamp). Best: large.
    uint64_t distinctValues = 0;
    // The part of [near, far] the format represents: [representableNear, representableFar].
    // Depths outside it are clamped to the stored value at its end (and fight each other).
    double representableNear = 0;
    double representableFar = 0;
    std::string rangeNote;           // empty, or why part of [near, far] is not representable
    std::vector<DepthResolutionSample> decades;  // at DepthAuditResult::decadeDepths
    std::vector<DepthFightDistance> fights;      // one per DepthAuditResult::fightGaps
    // Dense curve for the plot: resolution at DepthAuditResult::curveDepths (absent where out of range).
    std::vector<std::optional<double>> curveResolution;
};

struct DepthAuditSettings {
    std::vector<double> fightGaps = {0.01, 0.001};  // surface gaps (m) for fight distances
    int curveSamples = 200;                         // dense-curve samples between near and far
};

struct DepthAuditResult {
    std::string error;               // empty = ok; otherwise what is wrong with the input and the fix
    double nearZ = 0, farZ = 0;      // the audited depth range [near, far]
    std::vector<double> decadeDepths;  // near, every 10^k strictly between, far
    std::vector<double> fightGaps;     // as DepthAuditSettings::fightGaps
    // Dense curve depths: geometric centers of curveSamples equal log-width bins over [near, far]
    // (strictly inside, so the singular end buckets of the clamping formats do not dominate).
    std::vector<double> curveDepths;
    std::vector<DepthFormatAudit> formats;  // in the order asked for
};

// Checks near/far: finite, 0 < near < far, far <= FLT_MAX (float formats must hold far).
// On failure returns false and *err names the value and the fix.
bool validateDepthAuditRange(double nearZ, double farZ, std::string *err);

// The audit. Invalid input (see validateDepthAuditRange and validateDepthFormatRange; also an
// empty or repeated format list, a gap that is not finite and > 0) returns a result with `error`
// set and no formats.
DepthAuditResult auditDepthFormats(double nearZ, double farZ, const std::vector<DepthFormatSpec> &formats,
                                   const DepthAuditSettings &settings = {});
// The same over plain formats (log24 with C = 1).
DepthAuditResult auditDepthFormats(double nearZ, double farZ, const std::vector<DepthFormat> &formats,
                                   const DepthAuditSettings &settings = {});
DepthAuditResult auditDepthFormats(double nearZ, double farZ, std::initializer_list<DepthFormat> formats,
                                   const DepthAuditSettings &settings = {});

// ---- Cheapest format ----------------------------------------------------------------------------
// Every format in the order "cheapest first": fewer bits of stored value first; among equal bits,
// by how much a renderer must change to use it: (1) a depth buffer with the standard projection,
// (2) the same buffer with reversed-Z (projection and depth test change), (3) API-specific
// variants of these (OpenGL's [-1, 1] window transform, WebGPU's names), (4) a shader-written
// logarithmic depth (costs early-Z), (5) formats no GPU depth buffer has (software z-buffers:
// linear_f32, inv_f32 and the integer 1/d formats). docs/depth-formats.md has the list.
const std::vector<DepthFormat> &depthFormatsCheapestFirst();

}  // namespace va
